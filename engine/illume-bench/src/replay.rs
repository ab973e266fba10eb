//! Scripted edits in time order: every consumer of a scenario (the converged reference,
//! each technique, the equal-time path tracer) replays the same edits at the same frames,
//! so each sees exactly the same scene states.

use crate::error::BenchError;
use crate::scenario::{EditSpec, Scenario};
use illume_engine::{Engine, read_world};
use illume_scene::Scene;
use illume_transport::World;

/// Something scripted edits can be applied to: a bare [`Scene`], a [`World`] (tracer and
/// lights follow) or an [`Engine`] (the technique is told).
pub trait EditTarget {
    /// Resolves `spec` against the current scene state and applies it.
    fn apply_spec(&mut self, spec: &EditSpec) -> Result<(), String>;
}

impl EditTarget for Scene {
    fn apply_spec(&mut self, spec: &EditSpec) -> Result<(), String> {
        let edit = spec.resolve(self)?;
        self.apply_edit(&edit).map(drop).map_err(|e| e.to_string())
    }
}

impl EditTarget for World {
    fn apply_spec(&mut self, spec: &EditSpec) -> Result<(), String> {
        let edit = spec.resolve(&self.scene)?;
        self.apply_edit(&edit).map(drop).map_err(|e| e.to_string())
    }
}

impl EditTarget for Engine {
    fn apply_spec(&mut self, spec: &EditSpec) -> Result<(), String> {
        let edit = spec.resolve(&read_world(self.world()).scene)?;
        self.apply_edit(&edit).map(drop).map_err(|e| e.to_string())
    }
}

/// The scenario's edits, handed out once each as frame time passes them.
pub struct Replay<'a> {
    scenario: &'a Scenario,
    order: Vec<usize>,
    next: usize,
}

impl<'a> Replay<'a> {
    /// The edits of `scenario`, none applied yet.
    pub fn new(scenario: &'a Scenario) -> Self {
        Self {
            scenario,
            order: scenario.edit_order(),
            next: 0,
        }
    }

    /// Applies, in order, every edit with `at_s ≤ t` not applied yet; returns their
    /// indices in the scenario's `[[edit]]` list. Call before rendering the frame at `t`.
    pub fn apply_due(
        &mut self,
        target: &mut dyn EditTarget,
        t: f64,
    ) -> Result<Vec<usize>, BenchError> {
        let mut applied = Vec::new();
        while let Some(&index) = self.order.get(self.next) {
            let spec = &self.scenario.edits[index];
            if spec.at_s > t {
                break;
            }
            target
                .apply_spec(spec)
                .map_err(|message| BenchError::Edit {
                    path: self.scenario.file.clone(),
                    index,
                    message,
                })?;
            applied.push(index);
            self.next += 1;
        }
        Ok(applied)
    }
}
