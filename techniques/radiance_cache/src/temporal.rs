//! The temporal weighting function (§4.2, Eq. 5–12) and temporal gradients (§4.4,
//! Eq. 13–23), as pure functions of records and frame indices.
//!
//! * **Change rate.** τ = E₁/E₀ (Eq. 7), E₀ a record's irradiance at its frame and E₁
//!   the estimate one frame later, taken on the RGB channel with the largest |τ − 1|.
//!   E₀ = 0 < E₁ is an infinite change; E₀ = E₁ = 0 none.
//! * **Weight and validity.** w^t(t) = 1/(|τ − 1|(t − t₀)) (Eq. 9, with the absolute
//!   value the paper omits: a darkening is as much a change as a brightening). A record
//!   is valid at t while w^t ≥ 1/a^t (Eq. 10) and t − t₀ < δt_max (Eq. 12); at t = t₀
//!   the weight is infinite. Both conditions together give a lifespan of
//!   1 + min(⌊a^t/|τ − 1|⌋, δt_max − 1) frames ([`lifespan_frames`]); validity at a frame
//!   is defined from it ([`is_valid`]), so the two never disagree by rounding.
//! * **Contribution over time.** Eq. 17: a record's Eq. 4 value with E_k, ∇_r and ∇_p
//!   moved along their temporal gradients by t − t_k, with the offset p − p_k as in
//!   Eq. 4 (the paper's Eq. 17 prints p_k − p).
//! * **Temporal gradients.** Extrapolated (Eq. 18–20): the next-frame estimate minus the
//!   record's values. Interpolated (Eq. 21–23): the replacing record's values minus
//!   the record's, over the frames between them.
//!
//! Frames are integer indices (the paper's t₁ − t₀ = 1); gradients are per frame.

use crate::RadianceCacheError;
use crate::record::{IrradianceRecord, IrradianceValue, interpolate_by};
use illume_core::{Rgb, Vec3};

/// |τ − 1| of Eq. 7 on the channel where it is largest, from E₀ (the record's frame) and
/// E₁ (one frame later): infinite when some channel goes from zero to a positive value
/// or when either value is not a number (a conservative answer: the record then lives
/// one frame); zero when nothing changes.
pub fn change_rate(e0: Rgb, e1: Rgb) -> f32 {
    let mut largest = 0.0f32;
    for c in 0..3 {
        let (a, b) = (e0[c], e1[c]);
        let change = if a.is_nan() || b.is_nan() {
            f32::INFINITY
        } else if a > 0.0 {
            (b / a - 1.0).abs()
        } else if b > 0.0 {
            f32::INFINITY
        } else {
            0.0
        };
        largest = largest.max(change);
    }
    largest
}

/// Eq. 9 with the absolute value: w^t = 1/(|τ − 1|·age), `change` = |τ − 1| and `age`
/// = t − t₀ frames; infinite when either is zero.
pub fn temporal_weight(change: f32, age_frames: u32) -> f32 {
    1.0 / (change * age_frames as f32)
}

/// A record's lifespan in frames, counting its own: 1 + min(⌊a^t/|τ − 1|⌋, δt_max − 1),
/// the number of frames t₀, t₀ + 1, … at which Eq. 10 (w^t ≥ 1/a^t) and Eq. 12
/// (t − t₀ < δt_max) both hold. `change` = |τ − 1| (see [`change_rate`]),
/// `temporal_accuracy` = a^t, `max_age_frames` = δt_max (taken as at least 1). A
/// non-positive or NaN a^t admits no frame after the first.
pub fn lifespan_frames(change: f32, temporal_accuracy: f32, max_age_frames: u32) -> u32 {
    let cap = max_age_frames.max(1) - 1;
    let extra = if change == 0.0 {
        cap
    } else {
        let ratio = (temporal_accuracy as f64 / change as f64).floor();
        // NaN and negative ratios give 0; `as` saturates large ones.
        if ratio >= 0.0 {
            (ratio.min(cap as f64)) as u32
        } else {
            0
        }
    };
    1 + extra
}

/// True when a record made at `record_frame` with `lifespan_frames` is valid at `frame`
/// (Eq. 10 and Eq. 12 through [`lifespan_frames`]); never before its own frame.
#[inline]
pub fn is_valid(record_frame: u32, lifespan_frames: u32, frame: u32) -> bool {
    frame >= record_frame && frame - record_frame < lifespan_frames
}

/// Eq. 17 at `p` with unit normal `n` at frame `frame`: E_k + ∇ᵗ_E(t − t_k) +
/// (n_k × n)·(∇_r + ∇ᵗ_∇r(t − t_k)) + (p − p_k)·(∇_p + ∇ᵗ_∇p(t − t_k)). With a zero
/// temporal gradient (or at t = t_k) it is Eq. 4.
pub fn contribution(record: &IrradianceRecord, p: Vec3, n: Vec3, frame: u32) -> Rgb {
    let dt = frame as f32 - record.frame as f32;
    (record.value + record.temporal_gradient * dt)
        .extrapolate(p - record.position, record.normal.cross(n))
}

/// Extrapolated temporal gradients, Eq. 18–20: `next` (the reprojected estimate at
/// t_k + 1) minus `now` (the record's values at t_k), per frame.
pub fn extrapolated_gradient(now: &IrradianceValue, next: &IrradianceValue) -> IrradianceValue {
    *next - *now
}

/// Interpolated temporal gradients, Eq. 21–23: (`replacement` − `record`)/(t_l − t_k),
/// from record k at `record_frame` = t_k and its replacement l at `replacement_frame` =
/// t_l. Errors unless t_l > t_k.
pub fn interpolated_gradient(
    record: &IrradianceValue,
    record_frame: u32,
    replacement: &IrradianceValue,
    replacement_frame: u32,
) -> Result<IrradianceValue, RadianceCacheError> {
    if replacement_frame <= record_frame {
        return Err(RadianceCacheError::TemporalOrder {
            from: record_frame,
            to: replacement_frame,
        });
    }
    Ok((*replacement - *record) * (1.0 / (replacement_frame - record_frame) as f32))
}

/// Eq. 1 at frame `frame`: over the records among `records` valid at that frame
/// ([`is_valid`]) and usable at `p` with unit normal `n` (Eq. 3 with `accuracy`), each
/// weighted by Eq. 2 and contributing by Eq. 17. `None` when none is.
pub fn interpolate_at<'a>(
    records: impl IntoIterator<Item = &'a IrradianceRecord>,
    p: Vec3,
    n: Vec3,
    accuracy: f32,
    frame: u32,
) -> Option<Rgb> {
    interpolate_by(records, p, n, accuracy, |r| {
        is_valid(r.frame, r.lifespan_frames, frame).then(|| contribution(r, p, n, frame))
    })
}
