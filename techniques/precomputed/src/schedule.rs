//! When to render keys (Bahnsen et al. Eq. 1, Eq. 3, §3.2 "Dynamically select the sampling
//! interval", Fig. 6), and how to find the two keys around a time.
//!
//! Times here are local clock hours ([`illume_scene::sun::SunSettings::clock_hours`]).
//!
//! - **Uniform** (Eq. 1): a key every ΔT from `from` to `to` inclusive, at `from + i·ΔT`
//!   for `i ≤ ⌊(to − from)/ΔT⌋` (0–24 h at 5 min: 289 keys, both midnights; 8–16 h hourly:
//!   9 keys, 16:00 included).
//! - **Adaptive** (§3.2): start from two equal intervals (keys at `from`, the middle and
//!   `to`: level 0). At each level, every interval made at the previous level whose length
//!   is at least 2 ΔT_min is tested: its ends are interpolated to its middle, and if the
//!   result differs noticeably (PerceptualDiff, [`illume_metrics::yee`]) from either end,
//!   the middle is rendered (this level's keys) and the interval splits. Keys therefore stay
//!   ≥ ΔT_min apart. Beyond the paper, [`Criterion::VerifyMidpoint`] renders every tested
//!   middle and keeps it only if the interpolation differs from it.
//!
//! Running level by level lets each level shard over machines (`--level L`).

/// A key time and the adaptive level that added it (0: the three first keys; uniform
/// keys are all level 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyTime {
    /// Local clock time \[hours\].
    pub hours: f64,
    /// Adaptive level that added it.
    pub level: u32,
}

/// What decides that an interval splits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Criterion {
    /// The paper's: the ends' interpolation at the middle differs from either end.
    #[default]
    Ends,
    /// Beyond the paper: the middle is rendered and the interpolation differs from it.
    VerifyMidpoint,
}

/// The smallest key image \[pixels\] on which the adaptive schedule was seen to place
/// keys by the light: on `builtin:sun-room` at 64×48 Yee's metric saw too little and every
/// lit hour sat at the daylight floor, at 160×120 and above keys gathered where the sun's
/// patch moves (docs/benchmarks/precomputed.md, "keys placed by the light").
pub const ADAPTIVE_MIN_PIXELS: u64 = 160 * 120;

/// What to tell a user who runs the adaptive schedule on key images of `width`×`height`
/// below [`ADAPTIVE_MIN_PIXELS`]; `None` at or above it.
pub fn small_image_warning(width: u32, height: u32) -> Option<String> {
    (u64::from(width) * u64::from(height) < ADAPTIVE_MIN_PIXELS).then(|| {
        format!(
            "precomputed: the adaptive schedule compares {width}×{height} key images; below \
             160×120 pixels Yee's metric sees too little and keeps about the daylight \
             floor's keys (1–2 an hour) instead of following the light: use a larger \
             --width/--height, or --schedule uniform"
        )
    })
}

/// Uniform keys from `from_h` to `to_h` inclusive (when `to_h` falls on a step) every
/// `step_min` minutes (Eq. 1), at most
/// [`crate::file::MAX_KEYS`] (the settings refuse a step that asks for more,
/// [`crate::settings::PrecomputedSettings::validate`]; the cap here only keeps an
/// unchecked caller from allocating without bound).
pub fn uniform(from_h: f64, to_h: f64, step_min: f64) -> Vec<KeyTime> {
    let step = step_min / 60.0;
    // + 1: the key at `to_h` itself (to a step's 10⁻⁹, so 8–16 h at 60 min is 9 keys
    // whatever the rounding of the division).
    let n = ((to_h - from_h) / step + 1e-9)
        .floor()
        .clamp(0.0, crate::file::MAX_KEYS as f64 - 1.0) as usize
        + 1;
    (0..n)
        .map(|i| KeyTime {
            hours: from_h + i as f64 * step,
            level: 0,
        })
        .collect()
}

/// The three keys of adaptive level 0: both ends and the middle.
pub fn adaptive_start(from_h: f64, to_h: f64) -> Vec<KeyTime> {
    [from_h, 0.5 * (from_h + to_h), to_h]
        .into_iter()
        .map(|hours| KeyTime { hours, level: 0 })
        .collect()
}

/// Intervals (pairs of indices into `keys`, sorted by time) to test at level `level + 1`:
/// consecutive keys of which at least one was added at `level` (older intervals passed
/// already) and that are at least `2 · min_step_min` minutes long.
pub fn open_intervals(keys: &[KeyTime], level: u32, min_step_min: f64) -> Vec<(usize, usize)> {
    let min_len = 2.0 * min_step_min / 60.0 - 1e-9;
    (1..keys.len())
        .filter(|&i| {
            let (a, b) = (keys[i - 1], keys[i]);
            (a.level == level || b.level == level) && b.hours - a.hours >= min_len
        })
        .map(|i| (i - 1, i))
        .collect()
}

/// The daylight floor of the adaptive schedule \[hours\]: an interval longer than this
/// with the sun above the horizon anywhere inside splits whatever the images say, so no
/// hour of daylight goes without a key (bisecting a day, daylight keys end up at most
/// 45 min apart). Night intervals, with black keys at both ends, are left alone. It holds
/// for `step_min` ≤ 30 min (keys stay ≥ `step_min` apart first).
pub const MAX_DAYLIGHT_GAP_H: f64 = 1.0;

/// A middle that adaptive level `level` tests: the midpoint of the interval between
/// keys `ends.0` and `ends.1` (indices into the keys of the levels before).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Middle {
    /// Its time \[hours\].
    pub hours: f64,
    /// The interval's keys.
    pub ends: (usize, usize),
}

/// The middles adaptive level `level` (≥ 1) renders, from the keys of the levels before
/// (sorted by time, with their images): the middles of the intervals made at level
/// `level − 1` that are at least `2 · min_step_min` long ([`open_intervals`]). Those
/// `forced(from_h, to_h)` says must split (the daylight floor, [`MAX_DAYLIGHT_GAP_H`]),
/// and with [`Criterion::Ends`] those whose ends' interpolation at the middle `differs`
/// from either end; with [`Criterion::VerifyMidpoint`] all of them (the rendered middle
/// then decides, [`keeps_middle`]). Empty: the schedule is complete.
pub fn level_middles<T>(
    keys: &[(KeyTime, T)],
    level: u32,
    min_step_min: f64,
    criterion: Criterion,
    forced: impl Fn(f64, f64) -> bool,
    mut differs: impl FnMut(&T, &T) -> bool,
    mut interpolate: impl FnMut(&T, &T, f32) -> T,
) -> Vec<Middle> {
    let times: Vec<KeyTime> = keys.iter().map(|k| k.0).collect();
    let Some(previous) = level.checked_sub(1) else {
        return Vec::new();
    };
    open_intervals(&times, previous, min_step_min)
        .into_iter()
        .filter(|&(a, b)| {
            forced(times[a].hours, times[b].hours)
                || match criterion {
                    Criterion::Ends => {
                        let mid = interpolate(&keys[a].1, &keys[b].1, 0.5);
                        differs(&mid, &keys[a].1) || differs(&mid, &keys[b].1)
                    }
                    Criterion::VerifyMidpoint => true,
                }
        })
        .map(|(a, b)| Middle {
            hours: 0.5 * (times[a].hours + times[b].hours),
            ends: (a, b),
        })
        .collect()
}

/// Whether a rendered middle becomes a key: always with [`Criterion::Ends`] (its interval
/// was split before rendering it) or when the daylight floor `forced` the split; with
/// [`Criterion::VerifyMidpoint`] otherwise when the ends' interpolation `differs` from
/// the rendered `image`.
pub fn keeps_middle<T>(
    criterion: Criterion,
    forced: bool,
    ends: (&T, &T),
    image: &T,
    mut differs: impl FnMut(&T, &T) -> bool,
    mut interpolate: impl FnMut(&T, &T, f32) -> T,
) -> bool {
    forced
        || match criterion {
            Criterion::Ends => true,
            Criterion::VerifyMidpoint => differs(&interpolate(ends.0, ends.1, 0.5), image),
        }
}

/// The whole adaptive schedule in one process: `render` makes the images of a batch of
/// times (it may run them in parallel), `differs(a, b)` says whether two images differ
/// noticeably, `interpolate(a, b, α)` blends two images, `forced(from_h, to_h)` says an
/// interval must split whatever its images (the daylight floor). Returns the keys
/// (sorted) with their images.
///
/// Level 0 is [`adaptive_start`]; level L ≥ 1 renders [`level_middles`] and keeps those
/// [`keeps_middle`] accepts, until a level keeps none. The sharded precompute
/// ([`crate::shard`]) runs the same two steps level by level, across machines.
#[expect(
    clippy::too_many_arguments,
    reason = "the span, the step, the criterion and the four steps it is generic over"
)]
pub fn adaptive<T, E>(
    from_h: f64,
    to_h: f64,
    min_step_min: f64,
    criterion: Criterion,
    forced: impl Fn(f64, f64) -> bool,
    mut render: impl FnMut(&[f64]) -> Result<Vec<T>, E>,
    mut differs: impl FnMut(&T, &T) -> bool,
    mut interpolate: impl FnMut(&T, &T, f32) -> T,
) -> Result<Vec<(KeyTime, T)>, E> {
    let start = adaptive_start(from_h, to_h);
    let hours: Vec<f64> = start.iter().map(|k| k.hours).collect();
    let mut keys: Vec<(KeyTime, T)> = start.into_iter().zip(render(&hours)?).collect();
    for level in 1.. {
        let middles = level_middles(
            &keys,
            level,
            min_step_min,
            criterion,
            &forced,
            &mut differs,
            &mut interpolate,
        );
        if middles.is_empty() {
            break;
        }
        let hours: Vec<f64> = middles.iter().map(|m| m.hours).collect();
        let images = render(&hours)?;
        let mut kept = Vec::new();
        for (m, image) in middles.iter().zip(images) {
            let ends = (&keys[m.ends.0].1, &keys[m.ends.1].1);
            let force = forced(keys[m.ends.0].0.hours, keys[m.ends.1].0.hours);
            if keeps_middle(
                criterion,
                force,
                ends,
                &image,
                &mut differs,
                &mut interpolate,
            ) {
                kept.push((
                    KeyTime {
                        hours: m.hours,
                        level,
                    },
                    image,
                ));
            }
        }
        if kept.is_empty() {
            break;
        }
        keys.extend(kept);
        keys.sort_by(|a, b| a.0.hours.total_cmp(&b.0.hours));
    }
    Ok(keys)
}

/// The keys around `hours` and the blend weight α of the later one (Eq. 3 generalised
/// to non-uniform keys: a binary search, then `α = (t − t_N)/(t_{N+1} − t_N)`). Times
/// before the first key or after the last clamp to it (α = 0 or 1). `times` should be
/// finite and strictly increasing (a file's are, [`crate::file::Header::check`]); any
/// other input still gives indices within `times` (or `(0, 0, 0.0)` when it is empty)
/// and an α in [0, 1], never a panic.
pub fn bracket(times: &[f64], hours: f64) -> (usize, usize, f32) {
    let last = times.len().saturating_sub(1);
    if times.is_empty() || hours <= times[0] || hours.is_nan() {
        return (0, 0, 0.0);
    }
    if hours >= times[last] || last == 0 {
        return (last, last, 0.0);
    }
    // First index with times[i] > hours (≥ 1, since hours > times[0]; clamped for
    // unsorted or NaN times).
    let next = times.partition_point(|&t| t <= hours).clamp(1, last);
    let n = next - 1;
    let alpha = ((hours - times[n]) / (times[next] - times[n])) as f32;
    let alpha = if alpha.is_nan() {
        0.0
    } else {
        alpha.clamp(0.0, 1.0)
    };
    (n, next, alpha)
}

#[cfg(test)]
mod tests {

    /// The adaptive schedule warns below 160×120 (where it was measured to sit at the
    /// daylight floor on `sun-room`), naming the size, and not at or above it.
    #[test]
    fn small_key_images_get_a_warning_naming_their_size() {
        let w = small_image_warning(64, 48).expect("64×48 is below the measured size");
        assert!(
            w.contains("64×48") && w.contains("--schedule uniform"),
            "{w}"
        );
        assert!(small_image_warning(159, 120).is_some());
        assert!(small_image_warning(160, 120).is_none());
        assert!(small_image_warning(702, 722).is_none());
        assert!(small_image_warning(u32::MAX, u32::MAX).is_none());
    }
    use super::*;

    /// A synthetic "image": one value, rendered from a function of the time.
    fn run(f: impl Fn(f64) -> f32, criterion: Criterion) -> Vec<KeyTime> {
        run_with(f, criterion, |_, _| false)
    }

    fn run_with(
        f: impl Fn(f64) -> f32,
        criterion: Criterion,
        forced: impl Fn(f64, f64) -> bool,
    ) -> Vec<KeyTime> {
        let keys = adaptive::<f32, ()>(
            0.0,
            24.0,
            5.0,
            criterion,
            forced,
            |times| Ok(times.iter().map(|&t| f(t)).collect()),
            |a, b| (a - b).abs() > 0.01,
            |a, b, alpha| a + (b - a) * alpha,
        )
        .unwrap();
        keys.into_iter().map(|k| k.0).collect()
    }

    /// `--to` is inclusive (issue 36: `--from 8 --to 16 --step-min 60` gave 8 keys, 16:00
    /// left out).
    #[test]
    fn uniform_includes_the_last_hour() {
        let hours = |from, to, step| -> Vec<f64> {
            uniform(from, to, step).iter().map(|k| k.hours).collect()
        };
        assert_eq!(
            hours(8.0, 16.0, 60.0),
            (8..=16).map(f64::from).collect::<Vec<_>>()
        );
        // A day at 5 min: the paper's 288 frames 0:00–23:55, and midnight at the end.
        let day = uniform(0.0, 24.0, 5.0);
        assert_eq!(day.len(), 289);
        assert!((day[287].hours - (24.0 - 5.0 / 60.0)).abs() < 1e-9);
        assert_eq!(day[288].hours, 24.0);
        // `to` off the grid: the last key is the last step before it.
        assert_eq!(hours(10.0, 11.0, 25.0).len(), 3);
        // 0.1 h steps whose sum rounds below 1: still 11 keys.
        assert_eq!(hours(0.0, 1.0, 6.0).len(), 11);
    }

    #[test]
    fn constant_sequence_keeps_only_the_first_keys() {
        let keys = run(|_| 0.5, Criterion::Ends);
        let hours: Vec<f64> = keys.iter().map(|k| k.hours).collect();
        assert_eq!(hours, vec![0.0, 12.0, 24.0]);
        let keys = run(|_| 0.5, Criterion::VerifyMidpoint);
        assert_eq!(keys.len(), 3);
    }

    /// A smooth step from 0 to 1 over [10 h, 10.8 h]: keys gather there, none closer than
    /// 5 min. (A linear ramp would fool [`Criterion::VerifyMidpoint`] once an interval's
    /// middle lands where the interpolation happens to be exact.)
    #[test]
    fn fast_change_puts_keys_only_there() {
        let (a, b) = (10.0, 10.8);
        let ramp = move |t: f64| {
            let x = ((t - a) / (b - a)).clamp(0.0, 1.0);
            (x * x * (3.0 - 2.0 * x)) as f32
        };
        for criterion in [Criterion::Ends, Criterion::VerifyMidpoint] {
            let keys = run(ramp, criterion);
            for w in keys.windows(2) {
                assert!(
                    w[1].hours - w[0].hours >= 5.0 / 60.0 - 1e-9,
                    "{criterion:?}: keys {} and {} closer than 5 min",
                    w[0].hours,
                    w[1].hours
                );
            }
            let inside = keys.iter().filter(|k| (a..=b).contains(&k.hours)).count();
            let outside: Vec<f64> = keys
                .iter()
                .filter(|k| !(a - 1.0..=b + 1.0).contains(&k.hours))
                .map(|k| k.hours)
                .collect();
            eprintln!("{criterion:?}: {} keys, {inside} in the step", keys.len());
            assert!(inside >= 6, "{criterion:?}: only {inside} keys in the step");
            // Outside only the bisection's way in: the three first keys and one per level
            // down to the ramp (0, 6, 12, 24 here).
            assert!(outside.len() <= 4, "{criterion:?}: {outside:?}");
        }
    }

    /// The daylight floor (issue 36): a constant day (nothing the images would split)
    /// still gets keys ≤ 1 h apart where the floor says so, and none elsewhere.
    #[test]
    fn the_floor_splits_daylight_hours_only() {
        let day = |a: f64, b: f64| b - a > MAX_DAYLIGHT_GAP_H && b > 6.0 && a < 18.0;
        for criterion in [Criterion::Ends, Criterion::VerifyMidpoint] {
            let keys = run_with(|_| 0.5, criterion, day);
            for w in keys.windows(2) {
                let (a, b) = (w[0].hours, w[1].hours);
                if b > 6.0 && a < 18.0 {
                    assert!(b - a <= MAX_DAYLIGHT_GAP_H, "{criterion:?}: {a}–{b} h");
                }
            }
            // The night (before 6 h, after 18 h) keeps the bisection's long intervals.
            assert!(
                keys.iter().filter(|k| k.hours < 6.0).count() <= 2,
                "{keys:?}"
            );
            assert!(
                keys.iter().filter(|k| k.hours > 18.0).count() <= 2,
                "{keys:?}"
            );
        }
    }

    /// Issue 38: a NaN key time (or an unsorted list) made `bracket` index before the
    /// first key; every answer must now be within the list.
    #[test]
    fn bracket_never_leaves_the_keys() {
        let lists: [&[f64]; 5] = [
            &[0.0, f64::NAN, 2.0],
            &[f64::NAN, 1.0, 2.0],
            &[3.0, 1.0, 2.0],
            &[1.0, 1.0, 1.0],
            &[f64::NAN],
        ];
        for times in lists {
            for hours in [-1.0, 0.5, 1.0, 1.5, 2.5, f64::NAN, f64::INFINITY] {
                let (n, m, alpha) = bracket(times, hours);
                assert!(n < times.len() && m < times.len(), "{times:?} at {hours}");
                assert!(
                    (0.0..=1.0).contains(&alpha),
                    "{times:?} at {hours}: {alpha}"
                );
            }
        }
        assert_eq!(bracket(&[], 1.0), (0, 0, 0.0));
    }

    #[test]
    fn bracket_finds_neighbours_and_alpha() {
        let times = [0.0, 1.0, 3.0, 7.0];
        assert_eq!(bracket(&times, 2.0), (1, 2, 0.5));
        assert_eq!(bracket(&times, 6.0), (2, 3, 0.75));
        assert_eq!(bracket(&times, 1.0), (1, 2, 0.0));
        assert_eq!(bracket(&times, -1.0), (0, 0, 0.0));
        assert_eq!(bracket(&times, 9.0), (3, 3, 0.0));
        // Uniform keys: the same as Eq. 1 and 3.
        let keys: Vec<f64> = uniform(0.0, 24.0, 5.0).iter().map(|k| k.hours).collect();
        let t = 13.0 + 17.0 / 60.0; // 13:17
        let (n, m, alpha) = bracket(&keys, t);
        assert_eq!(n, ((13 * 60 + 17) as f64 / 5.0).floor() as usize);
        assert_eq!(m, n + 1);
        assert!((alpha - 2.0 / 5.0).abs() < 1e-5);
    }
}
