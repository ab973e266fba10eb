//! Shared light transport: the Technique trait, surface interactions, BSDFs, light sampling and photon paths.
