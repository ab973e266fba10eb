//! Culling (§0.7.3, CPU form): which VSLs may light a tile of the screen.
//!
//! For each tile the world box of its G-buffer points is computed, and a VSL is kept if
//! its influence sphere of radius r_ε = sqrt(Φ_s·R_max/(π ε)) (R_max = the tile's largest
//! ρ/π) meets the box and the box is not entirely behind the VSL's emitting side(s)
//! (cosθ' ≤ 0 everywhere). With a near field, a VSL whose light over the whole box is
//! gathered is left out too ([`crate::near_field`]).

use crate::shade::{VslField, far_weight};
use illume_core::{Aabb, PI};

/// VSLs of `field` that may light any point of `bounds` (see the module doc). With a
/// near field (`near_scale2` > 0, the window's squared scale) a VSL whose far-field
/// weight is 0 over the whole box (every corner inside its inner radius) is left out
/// too: its light there is all gathered.
pub fn cull(
    field: &VslField,
    bounds: &Aabb,
    max_reflectance: f32,
    epsilon: f32,
    near_scale2: f32,
    out: &mut Vec<u32>,
) {
    out.clear();
    let corners = bounds.corners();
    for s in 0..field.len() {
        let (pf, pb) = (
            field.front_w[s].max_element(),
            field.back_w[s].max_element(),
        );
        if pf <= 0.0 && pb <= 0.0 {
            continue;
        }
        let p = field.positions[s];
        if epsilon > 0.0 {
            let r2 = pf.max(pb) * max_reflectance / (PI * epsilon);
            let closest = p.clamp(bounds.min, bounds.max);
            if closest.distance_squared(p) > r2 {
                continue;
            }
        }
        if near_scale2 > 0.0 {
            let farthest = corners
                .iter()
                .map(|c| c.distance_squared(p))
                .fold(0.0f32, f32::max);
            if far_weight(farthest, field.area_m2[s], near_scale2) <= 0.0 {
                continue;
            }
        }
        let n = field.normals[s];
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for c in &corners {
            let h = n.dot(*c - p);
            lo = lo.min(h);
            hi = hi.max(h);
        }
        // Points within 0.1 mm of the VSL's plane get cosθ' ≈ 0: nothing to add.
        let tol = 1e-4;
        if (pf > 0.0 && hi > tol) || (pb > 0.0 && lo < -tol) {
            out.push(s as u32);
        }
    }
}
