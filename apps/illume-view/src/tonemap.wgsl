// The HDR frame to the screen: exposure, then the very curve of
// illume_core::image::ToneMap::apply (Narkowicz's ACES fit, Reinhard or clamp), then the
// sRGB transfer of illume_core::image::srgb_encode — the window shows what a PNG would.

struct Params {
    // 2^exposure_ev.
    scale: f32,
    // 0 clamp, 1 Reinhard, 2 ACES (illume_core::image::ToneCurve).
    curve: u32,
    // Size of the HDR texture [texels].
    size: vec2<u32>,
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

fn srgb_encode(x: f32) -> f32 {
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

fn tone(c: vec3<f32>) -> vec3<f32> {
    let x = max(c * params.scale, vec3<f32>(0.0));
    var y = x;
    if params.curve == 1u {
        y = x / (vec3<f32>(1.0) + x);
    } else if params.curve == 2u {
        y = (x * (x * 2.51 + 0.03)) / (x * (x * 2.43 + 0.59) + 0.14);
    }
    return clamp(y, vec3<f32>(0.0), vec3<f32>(1.0));
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    // Nearest texel (the upscale of a reduced resolution is blocky, never blurred).
    let texel = min(vec2<u32>(in.uv * vec2<f32>(params.size)), params.size - vec2<u32>(1u));
    let d = tone(textureLoad(frame, texel, 0).rgb);
    return vec4<f32>(srgb_encode(d.x), srgb_encode(d.y), srgb_encode(d.z), 1.0);
}
