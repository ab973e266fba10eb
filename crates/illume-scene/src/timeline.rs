//! The frames of a sequence known in advance, for techniques that use the future
//! (temporal radiance caching's records over the next frames, precomputed key frames).
//!
//! A [`Timeline`] lists the scene times of the frames about to be rendered, in render
//! order (a ping-pong sequence goes forward then back, so times repeat), with the image
//! size, and evaluates the scene at any of them on a copy: the live world is never
//! touched. Edits made while rendering (a bench scenario's `[[edit]]`, the viewer) are not
//! on the timeline; techniques learn of them as scene changes, as surprises.

use crate::model::Scene;

/// Why a timeline was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TimelineError {
    /// No frame times.
    #[error("a timeline needs at least one frame time")]
    Empty,
    /// A frame time is NaN or infinite.
    #[error("frame {index}: time {time} s is not finite")]
    NotFinite {
        /// Frame index.
        index: usize,
        /// The time given.
        time: f64,
    },
    /// The image has no pixels.
    #[error("image size {width}×{height} has no pixels")]
    EmptyImage {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
}

/// The frame times of a sequence, its image size, and the scene they animate.
#[derive(Clone, Debug)]
pub struct Timeline {
    times: Vec<f64>,
    width: u32,
    height: u32,
    scene: Scene,
}

impl Timeline {
    /// A timeline of `times` (scene seconds, in render order) for `scene` rendered at
    /// `width × height`. `scene` is the state the animation is evaluated from (as loaded,
    /// or as edited before rendering starts).
    pub fn new(
        scene: Scene,
        times: Vec<f64>,
        width: u32,
        height: u32,
    ) -> Result<Self, TimelineError> {
        if times.is_empty() {
            return Err(TimelineError::Empty);
        }
        if let Some((index, &time)) = times.iter().enumerate().find(|(_, t)| !t.is_finite()) {
            return Err(TimelineError::NotFinite { index, time });
        }
        if width == 0 || height == 0 {
            return Err(TimelineError::EmptyImage { width, height });
        }
        Ok(Self {
            times,
            width,
            height,
            scene,
        })
    }

    /// A one-frame timeline (a still) at time `t`. A non-finite `t` is replaced by 0
    /// and a zero size by 1 pixel, so this never fails; callers validate their inputs
    /// first.
    pub fn single(scene: Scene, t: f64, width: u32, height: u32) -> Self {
        Self {
            times: vec![if t.is_finite() { t } else { 0.0 }],
            width: width.max(1),
            height: height.max(1),
            scene,
        }
    }

    /// Frame times in render order \[s\].
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Always false: a timeline has at least one frame.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The scene the timeline animates, at the state it was given in.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene at frame `i`'s time (a copy; meshes and textures are shared, not
    /// copied), or `None` past the last frame.
    pub fn scene_at(&self, i: usize) -> Option<Scene> {
        self.times.get(i).map(|&t| self.scene_at_time(t))
    }

    /// The scene at any time `t` \[s\] (a copy, as [`Timeline::scene_at`]).
    pub fn scene_at_time(&self, t: f64) -> Scene {
        let mut scene = self.scene.clone();
        scene.set_time(t);
        scene
    }

    /// The first frame whose time is `t` exactly, if any: a time not on the timeline
    /// is a surprise to techniques that planned for the timeline.
    pub fn frame_of(&self, t: f64) -> Option<usize> {
        self.times.iter().position(|&x| x == t)
    }
}

/// Scene time of sequence time `t` for an animation of `animation_s` seconds: `t` itself,
/// or with `ping_pong`, forward over the animation then back (period 2·`animation_s`).
pub fn ping_pong_time(t: f64, animation_s: f64, ping_pong: bool) -> f64 {
    if !ping_pong || animation_s <= 0.0 {
        return t;
    }
    let period = 2.0 * animation_s;
    let u = t.rem_euclid(period);
    if u <= animation_s { u } else { period - u }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scene_at_matches_the_live_scene_and_leaves_it_alone() {
        let live = crate::builtin::load("cornell-spot").unwrap();
        let timeline = Timeline::new(live.clone(), vec![0.0, 0.5, 1.0], 8, 6).unwrap();
        let later = timeline.scene_at(2).unwrap();
        let mut expected = live.clone();
        expected.set_time(1.0);
        for (a, b) in later.instances.iter().zip(&expected.instances) {
            assert_eq!(a.world_from_object, b.world_from_object);
        }
        assert_ne!(
            later
                .instances
                .iter()
                .map(|i| i.world_from_object)
                .collect::<Vec<_>>(),
            live.instances
                .iter()
                .map(|i| i.world_from_object)
                .collect::<Vec<_>>(),
            "the sphere moves between 0 and 1 s"
        );
        // Meshes are shared, not copied.
        assert!(std::sync::Arc::ptr_eq(&later.meshes[0], &live.meshes[0]));
        assert!(timeline.scene_at(3).is_none());
        assert_eq!(timeline.frame_of(0.5), Some(1));
        assert_eq!(timeline.frame_of(0.25), None);
    }

    #[test]
    fn bad_timelines_are_refused() {
        let s = Scene::default();
        assert_eq!(
            Timeline::new(s.clone(), vec![], 4, 4).unwrap_err(),
            TimelineError::Empty
        );
        assert!(matches!(
            Timeline::new(s.clone(), vec![0.0, f64::NAN], 4, 4),
            Err(TimelineError::NotFinite { index: 1, .. })
        ));
        assert!(matches!(
            Timeline::new(s, vec![0.0], 0, 4),
            Err(TimelineError::EmptyImage { .. })
        ));
    }

    #[test]
    fn ping_pong_goes_forward_then_back() {
        assert_eq!(ping_pong_time(0.5, 2.0, true), 0.5);
        assert_eq!(ping_pong_time(3.0, 2.0, true), 1.0);
        assert_eq!(ping_pong_time(4.5, 2.0, true), 0.5);
        assert_eq!(ping_pong_time(3.0, 2.0, false), 3.0);
        assert_eq!(ping_pong_time(3.0, 0.0, true), 3.0);
    }
}
