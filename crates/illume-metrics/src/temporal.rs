//! Temporal metrics over an image sequence and its reference sequence: flicker, latency
//! after an event, and error-versus-time curves.

use crate::compare::{CompareSettings, Metric, measure};
use crate::error::{MetricsError, check_not_empty, check_same_size};
use illume_core::image::RgbImage;
use rayon::prelude::*;

/// Flicker of a sequence, per consecutive frame pair and overall.
///
/// Definition (luminance `Y` = Rec.709 weights of linear RGB, in the images' units): for
/// the frame pair `(k−1, k)` and pixel `p`,
///
/// ```text
/// flicker_k = mean_p max(0, |Y_test,k(p) − Y_test,k−1(p)| − |Y_ref,k(p) − Y_ref,k−1(p)|)
/// ```
///
/// i.e. the frame-to-frame change of the test beyond the change the reference itself
/// shows (real motion or lighting changes are not flicker). Zero for a sequence that
/// changes exactly as its reference does, or less. Example: a static reference and a
/// test that alternates `r ± δ` has `|ΔY_test| = 2δ`, `|ΔY_ref| = 0`, so every pair scores
/// exactly `2δ`.
#[derive(Clone, Debug, PartialEq)]
pub struct Flicker {
    /// `flicker_k` for k = 1..n (entry `i` is the pair of frames `i` and `i + 1`).
    pub per_pair: Vec<f64>,
    /// Mean over the pairs.
    pub mean: f64,
    /// Largest pair value.
    pub max: f64,
}

/// The flicker of `test` against `reference` (same length ≥ 2, all frames one size).
pub fn flicker(test: &[RgbImage], reference: &[RgbImage]) -> Result<Flicker, MetricsError> {
    if test.len() != reference.len() {
        return Err(MetricsError::LengthMismatch {
            what: "test and reference sequences",
            left: test.len(),
            right: reference.len(),
        });
    }
    if test.len() < 2 {
        return Err(MetricsError::TooFewFrames {
            what: "flicker",
            min: 2,
            got: test.len(),
        });
    }
    for (t, r) in test.iter().zip(reference) {
        check_same_size(&reference[0], r)?;
        check_same_size(r, t)?;
    }
    check_not_empty(&reference[0], "flicker")?;
    let luminance = |img: &RgbImage| -> Vec<f64> {
        img.pixels()
            .iter()
            .map(|&p| illume_core::luminance(p) as f64)
            .collect()
    };
    let test_y: Vec<Vec<f64>> = test.par_iter().map(luminance).collect();
    let ref_y: Vec<Vec<f64>> = reference.par_iter().map(luminance).collect();
    let per_pair: Vec<f64> = (1..test.len())
        .map(|k| {
            let n = test_y[k].len();
            (0..n)
                .map(|p| {
                    let dt = (test_y[k][p] - test_y[k - 1][p]).abs();
                    let dr = (ref_y[k][p] - ref_y[k - 1][p]).abs();
                    (dt - dr).max(0.0)
                })
                .sum::<f64>()
                / n as f64
        })
        .collect();
    let mean = per_pair.iter().sum::<f64>() / per_pair.len() as f64;
    let max = per_pair.iter().copied().fold(0.0, f64::max);
    Ok(Flicker {
        per_pair,
        mean,
        max,
    })
}

/// How long the error took to settle after an event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Latency {
    /// Frames from the event frame to the first frame from which the error stays below
    /// the threshold until the end; `None` if it never settles.
    pub frames: Option<usize>,
    /// The same in seconds (difference of the timestamps); `None` if it never settles.
    pub seconds: Option<f64>,
}

/// Latency after an event: given per-frame errors against the reference (any metric where
/// lower is better), their timestamps in seconds, and the frame at which the event (a
/// light switched, an object moved) happens, the number of frames `k ≥ 0` such that
/// `errors[event + k..]` are all below `threshold` and `k` is smallest. `k = 0` means the
/// error never rose above the threshold. Fails if `errors` and `times_s` differ in length
/// or `event_frame` is past the end.
pub fn latency_after_event(
    errors: &[f64],
    times_s: &[f64],
    event_frame: usize,
    threshold: f64,
) -> Result<Latency, MetricsError> {
    if errors.len() != times_s.len() {
        return Err(MetricsError::LengthMismatch {
            what: "errors and timestamps",
            left: errors.len(),
            right: times_s.len(),
        });
    }
    if event_frame >= errors.len() {
        return Err(MetricsError::InvalidArgument(format!(
            "event frame {event_frame} is past the last frame ({})",
            errors.len().saturating_sub(1)
        )));
    }
    // The last frame at or after the event whose error is not below the threshold.
    let last_bad = (event_frame..errors.len())
        .rev()
        .find(|&i| errors[i] >= threshold || errors[i].is_nan());
    let settled_at = match last_bad {
        None => Some(event_frame),
        Some(i) if i + 1 < errors.len() => Some(i + 1),
        Some(_) => None,
    };
    Ok(Latency {
        frames: settled_at.map(|s| s - event_frame),
        seconds: settled_at.map(|s| times_s[s] - times_s[event_frame]),
    })
}

/// A metric over time for one technique: the curve plotted in "error vs time".
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorCurve {
    /// The technique (or series) name.
    pub technique: String,
    /// The metric measured.
    pub metric: Metric,
    /// Timestamp of each frame in seconds.
    pub times_s: Vec<f64>,
    /// The metric of each frame against its reference frame.
    pub values: Vec<f64>,
}

impl ErrorCurve {
    /// `(time, value)` pairs.
    pub fn points(&self) -> Vec<(f64, f64)> {
        self.times_s
            .iter()
            .copied()
            .zip(self.values.iter().copied())
            .collect()
    }

    /// Latency after `event_frame` for this curve (see [`latency_after_event`]).
    pub fn latency(&self, event_frame: usize, threshold: f64) -> Result<Latency, MetricsError> {
        latency_after_event(&self.values, &self.times_s, event_frame, threshold)
    }
}

/// Measures `metric` for every frame of `frames` against the same frame of `references`.
pub fn error_curve(
    technique: &str,
    frames: &[RgbImage],
    references: &[RgbImage],
    times_s: &[f64],
    metric: Metric,
    settings: &CompareSettings,
) -> Result<ErrorCurve, MetricsError> {
    if frames.len() != references.len() {
        return Err(MetricsError::LengthMismatch {
            what: "frames and references",
            left: frames.len(),
            right: references.len(),
        });
    }
    if frames.len() != times_s.len() {
        return Err(MetricsError::LengthMismatch {
            what: "frames and timestamps",
            left: frames.len(),
            right: times_s.len(),
        });
    }
    let values = frames
        .iter()
        .zip(references)
        .map(|(f, r)| measure(r, f, metric, settings))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(ErrorCurve {
        technique: technique.to_owned(),
        metric,
        times_s: times_s.to_vec(),
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::Rgb;

    fn gradient(w: u32, h: u32) -> RgbImage {
        let mut img = RgbImage::black(w, h);
        for y in 0..h {
            for x in 0..w {
                *img.get_mut(x, y) = Rgb::new(x as f32 / w as f32, y as f32 / h as f32, 0.5);
            }
        }
        img
    }

    #[test]
    fn static_sequence_has_no_flicker() {
        let frames = vec![gradient(8, 8); 5];
        let f = flicker(&frames, &frames).unwrap();
        assert_eq!(f.per_pair, vec![0.0; 4]);
        assert_eq!(f.mean, 0.0);
    }

    #[test]
    fn alternating_noise_flickers_by_two_delta() {
        // Static reference r; test frame k = r + (−1)^k·δ on every channel, so
        // Y_test,k = Y_ref + (−1)^k·δ (the luminance weights sum to 1). Between consecutive
        // frames |ΔY_test| = 2δ and |ΔY_ref| = 0, hence flicker_k = max(0, 2δ − 0) = 2δ
        // at every pixel and for every pair.
        let delta = 0.05f32;
        let r = gradient(16, 8).map(|p| *p + Rgb::splat(0.1));
        let reference = vec![r.clone(); 6];
        let test: Vec<RgbImage> = (0..6)
            .map(|k| {
                let s = if k % 2 == 0 { delta } else { -delta };
                r.map(|p| *p + Rgb::splat(s))
            })
            .collect();
        let f = flicker(&test, &reference).unwrap();
        assert_eq!(f.per_pair.len(), 5);
        for v in &f.per_pair {
            assert!((v - 2.0 * delta as f64).abs() < 1e-6, "{v}");
        }
        assert!((f.mean - 0.1).abs() < 1e-6);
    }

    #[test]
    fn change_shared_with_the_reference_is_not_flicker() {
        let a = gradient(8, 8);
        let b = a.map(|p| *p * 2.0);
        let f = flicker(&[a.clone(), b.clone()], &[a, b]).unwrap();
        assert_eq!(f.per_pair, vec![0.0]);
    }

    #[test]
    fn flicker_rejects_mismatched_sequences() {
        let a = gradient(8, 8);
        assert!(matches!(
            flicker(std::slice::from_ref(&a), std::slice::from_ref(&a)),
            Err(MetricsError::TooFewFrames { .. })
        ));
        assert!(matches!(
            flicker(&[a.clone(), a.clone()], std::slice::from_ref(&a)),
            Err(MetricsError::LengthMismatch { .. })
        ));
    }

    #[test]
    fn latency_of_a_step_is_the_constructed_frame_count() {
        // 30 fps. Error 0.01 until the event at frame 10, then 1.0 for frames 10..=16 with a
        // transient dip at frame 13 (it does not "stay"), then 0.01 from frame 17 on.
        let fps = 30.0;
        let n = 40;
        let mut errors = vec![0.01; n];
        for e in &mut errors[10..17] {
            *e = 1.0;
        }
        errors[13] = 0.001;
        let times: Vec<f64> = (0..n).map(|i| i as f64 / fps).collect();
        let l = latency_after_event(&errors, &times, 10, 0.05).unwrap();
        assert_eq!(l.frames, Some(7));
        assert!((l.seconds.unwrap() - 7.0 / fps).abs() < 1e-12);
        // Never rising above the threshold: zero latency.
        assert_eq!(
            latency_after_event(&errors, &times, 20, 0.05)
                .unwrap()
                .frames,
            Some(0)
        );
        // Never settling: None.
        let mut bad = errors.clone();
        bad[n - 1] = 1.0;
        assert_eq!(
            latency_after_event(&bad, &times, 10, 0.05).unwrap(),
            Latency {
                frames: None,
                seconds: None
            }
        );
        assert!(latency_after_event(&errors, &times, n, 0.05).is_err());
    }

    #[test]
    fn error_curve_measures_each_frame() {
        let r = gradient(12, 12);
        let frames: Vec<RgbImage> = (0..3)
            .map(|k| r.map(|p| *p + Rgb::splat(0.25 * k as f32)))
            .collect();
        let refs = vec![r; 3];
        let c = error_curve(
            "t",
            &frames,
            &refs,
            &[0.0, 0.5, 1.0],
            Metric::Rmse,
            &CompareSettings::default(),
        )
        .unwrap();
        for (v, expected) in c.values.iter().zip([0.0, 0.25, 0.5]) {
            assert!((v - expected).abs() < 1e-6, "{v}");
        }
        assert_eq!(c.points()[2].0, 1.0);
    }
}
