//! CPU renderer: G-buffer, direct light with shadows, a technique's indirect light, HDR frames.
