//! Settings of the reference path tracer, as a tuning guide.

/// Reference path tracer settings (`[reference]` table).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReferenceSettings {
    /// Image width \[pixels\] (full-image rendering). Default 640.
    pub width: u32,
    /// Image height \[pixels\]. Default 480.
    pub height: u32,
    /// Samples per pixel of a full render. Noise falls as 1/√spp, time grows linearly.
    /// Default 256.
    pub spp: u32,
    /// Samples per pixel a [`ReferenceTechnique`](crate::ReferenceTechnique) adds each
    /// frame (indirect-only, progressive while the scene is static). Default 4.
    pub spp_per_frame: u32,
    /// Bounces before Russian roulette may end a path. Lower: faster, noisier deep
    /// paths (still unbiased). Default 3.
    pub rr_start_depth: u32,
    /// Hard limit on bounces, a safety net (Russian roulette ends paths long before in
    /// any scene with albedo < 1). Default 1024.
    pub max_depth: u32,
    /// Seed; the same seed gives the same image, bit for bit. Default 0.
    pub seed: u64,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            spp: 256,
            spp_per_frame: 4,
            rr_start_depth: 3,
            max_depth: 1024,
            seed: 0,
        }
    }
}
