// The frame to the screen: its texels are already the bytes of PNG output (tone-mapped
// and sRGB-encoded on the CPU by illume_core's own code, present.rs `display_bytes`) and
// the surface format is not sRGB, so they pass through unchanged.

struct Params {
    // Size of the frame's texture [texels].
    size: vec2<u32>,
    pad: vec2<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var frame: texture_2d<f32>;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

// One triangle covering the viewport.
@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> VertexOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    // Nearest texel (the upscale of a reduced resolution is blocky, never blurred).
    let texel = min(vec2<u32>(in.uv * vec2<f32>(params.size)), params.size - vec2<u32>(1u));
    return vec4<f32>(textureLoad(frame, texel, 0).rgb, 1.0);
}
