//! Shadow maps for the analytic lights (point, spot, directional): a depth image per light
//! (six for a point light) rendered each frame with the CPU rasterizer of [`illume_transport::raster`],
//! then looked up instead of casting one BVH shadow ray per pixel and light.
//!
//! Photon streaming (Meneveaux & Bridault 2008, §0.7.3): "for each light source, compute
//! the corresponding shadow map and estimate direct light contribution". Views:
//!
//! * spot — one perspective map along the axis whose square field of view covers the
//!   outer cone (cones wider than [`MAX_SPOT_MAP_HALF_ANGLE_RAD`] get a cube map: a
//!   single perspective map that wide spends most texels far off axis);
//! * point — a cube map: six 90° perspective faces (slightly wider, so that filtering
//!   near a face border reads texels of the same face);
//! * directional — one orthographic map fitted to the scene's bounding box.
//!
//! A map texel stores the depth of the nearest surface along the view axis (perspective:
//! `w`, the distance along the face's axis; orthographic: the distance along the light
//! direction from the plane through the scene centre) as `f32`, `∞` where nothing is seen.
//!
//! # Lookup
//!
//! The shading point is first pushed off its surface along the geometric normal by
//! [`ShadowMapSettings::normal_offset_texels`] texel footprints, projected, and compared
//! with a depth bias of `footprint · (depth_bias_texels + slope_bias_texels · tanθ)`
//! (θ between the normal and the light, tanθ capped at 10), where the footprint is the
//! world size of one texel at the point's depth. Percentage-closer filtering averages the
//! comparisons of a [`ShadowMapSettings::pcf_texels`]-wide square of texels with
//! bilinear weights, so visibility is a fraction in [0, 1] that varies smoothly across
//! shadow edges (over about one footprint times the kernel width).
//!
//! # Where maps and rays differ
//!
//! Only near shadow edges: a texel-sized band is blurred by the filter, and contacts
//! (an object resting on a floor) leak light within about one footprint of the contact
//! because of the bias — as do surfaces lit at an angle, whose slope-scaled bias reaches
//! several footprints (a fold of the Cornell dragon a few cm from the surface it
//! shades). Points lit more grazing than [`ShadowMapSettings::ray_below_cos`] (78° from
//! their normal by default) keep the map's answer only where it is "fully shadowed";
//! otherwise they take an exact ray, because there a texel covers many times its own
//! size of surface and the offsets let light past mouldings and arches (a low sun along
//! Sponza's walls). Everywhere else the bias keeps lit surfaces lit (no "acne") and
//! occluders further than the bias from the receiver shadow exactly.

use glam::{Affine3A, Mat3, Vec2, Vec3, Vec4};
use illume_transport::lights::{Emitter, LightSample};
use illume_transport::raster::{StoredDepth, Viewport, rasterize_depth};
use illume_transport::surface::SurfaceHit;
use illume_transport::world::World;
use rayon::prelude::*;

/// Spot lights whose outer cone half-angle exceeds this \[rad\] (60°) are mapped with a
/// cube map like point lights.
pub const MAX_SPOT_MAP_HALF_ANGLE_RAD: f32 = std::f32::consts::FRAC_PI_3;

/// Largest map side accepted \[texels\]: the rasterizer's guard band keeps its integer edge
/// functions exact up to 2¹⁴ pixels on a side, and 8192² f32 texels are already 256 MB.
pub const MAX_RESOLUTION: u32 = 8192;

/// Largest percentage-closer filter width accepted \[texels\].
pub const MAX_PCF_TEXELS: u32 = 8;

/// Steepest slope the slope-scaled bias follows (tan 84°); beyond it, the normal offset
/// does the work.
const MAX_SLOPE: f32 = 10.0;

/// Shadow-map quality and bias, a tuning guide. Used wherever the renderer's `shadows`
/// gives a light maps (`maps`, or `auto`'s choice); exact shadow rays ignore it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadowMapSettings {
    /// Side of the square map of a spot or directional light \[texels\]. Higher: sharper,
    /// more accurate shadow edges (the filtered band shrinks with the texel) and less bias,
    /// at a cost that grows with the texel count (memory 4 bytes/texel, the rasterizer's
    /// per-texel work). Default 1024.
    pub resolution: u32,
    /// Side of each of a point light's six cube faces \[texels\]. Same trade-off as
    /// `resolution`, six times over; a 90° face at 512 has about the texel density of a
    /// 70° spot map at 1024 at the same distance. Default 512.
    pub cube_face_resolution: u32,
    /// Constant depth bias \[texel footprints\]: how much further than a map texel a point
    /// must be to count as shadowed. Higher: fewer wrongly dark spots on lit surfaces
    /// ("acne"), at the cost of light leaking under occluders that touch the receiver.
    /// Default 0.5.
    pub depth_bias_texels: f32,
    /// Slope-scaled depth bias \[texel footprints per unit of tanθ\], θ the angle between
    /// the surface normal and the light (tanθ capped at 10). Surfaces lit at grazing angles
    /// change depth fastest across a texel and need the most. Higher: no acne at grazing
    /// light, at the cost of more leaking there. Default 1.0.
    pub slope_bias_texels: f32,
    /// Normal offset \[texel footprints\]: the shading point is moved this far along its
    /// geometric normal before the lookup, which removes acne at every angle with less
    /// leaking than a depth bias alone. Higher: no acne, at the cost of shadows shifted by
    /// up to that distance and light let past mouldings and ledges within it. Default 0:
    /// with grazing light on rays (`ray_below_cos`) the depth and slope biases keep lit
    /// surfaces lit, and with one footprint (and no rays) direct light in sunlit Sponza
    /// was +0.5 % to +27 % too bright against rays (−0.2 % to +5 % without it), Sibenik
    /// under a spot +6.8 % (+2.3 %) (`examples/shadow_map_error.rs`, `BENCHMARKS.md`).
    pub normal_offset_texels: f32,
    /// Width of the percentage-closer filter \[texels\]: 1 compares one texel (hard,
    /// aliased edges); k ≥ 2 averages k × k comparisons with bilinear weights (2 is the
    /// hardware-style bilinear filter). Higher: softer, less aliased edges, at the cost of
    /// k² comparisons per lookup and a wider blurred band along each shadow edge (the
    /// pixels that differ from exact rays). Default 2.
    pub pcf_texels: u32,
    /// Grazing light takes rays \[cos θ\]: a point lit at cos θ below this (θ between its
    /// geometric normal and the light) that the map calls lit, even partly, gets an exact
    /// shadow ray instead (one the map calls fully shadowed stays so). There a texel
    /// stretches over 1/cos θ of the surface and the slope-scaled bias and normal offset
    /// reach several footprints, enough to let light past mouldings and arches
    /// (direct light in sunlit Sponza at 9:37, whose walls the sun grazes at cos θ ≈
    /// 0.1–0.2: +5 % against rays at 0, +2.9 % at 0.1, +0.0 % at 0.2; Sibenik under a
    /// spot: +2.3 / +1.9 / +0.7 %). Higher: exact shadows over more of the surfaces lit
    /// at an angle, at the cost of one ray each (0.2: 2–3.5 ms more direct light a frame
    /// at 800×600 in Sponza and Sibenik under a spot, 0.1: under 1 ms; `BENCHMARKS.md`).
    /// 0: maps everywhere, the paper's choice (§0.7.3); 1: rays everywhere. Default 0.2
    /// (78° from the normal).
    pub ray_below_cos: f32,
}

impl Default for ShadowMapSettings {
    fn default() -> Self {
        Self {
            resolution: 1024,
            cube_face_resolution: 512,
            depth_bias_texels: 0.5,
            slope_bias_texels: 1.0,
            normal_offset_texels: 0.0,
            pcf_texels: 2,
            ray_below_cos: 0.2,
        }
    }
}

/// Why shadow-map settings were rejected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ShadowMapError {
    /// A setting is outside its allowed range.
    #[error("shadow_maps.{field} = {value}: must be in {min}..={max}")]
    OutOfRange {
        /// The setting's name.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
    },
}

impl ShadowMapSettings {
    /// Checks every setting's range.
    pub fn validate(&self) -> Result<(), ShadowMapError> {
        let check = |field, value: f64, min: f64, max: f64| {
            if (min..=max).contains(&value) {
                Ok(())
            } else {
                Err(ShadowMapError::OutOfRange {
                    field,
                    value,
                    min,
                    max,
                })
            }
        };
        let max = MAX_RESOLUTION as f64;
        check("resolution", self.resolution as f64, 1.0, max)?;
        check(
            "cube_face_resolution",
            self.cube_face_resolution as f64,
            1.0,
            max,
        )?;
        check("depth_bias_texels", self.depth_bias_texels as f64, 0.0, 1e3)?;
        check("slope_bias_texels", self.slope_bias_texels as f64, 0.0, 1e3)?;
        check(
            "normal_offset_texels",
            self.normal_offset_texels as f64,
            0.0,
            1e3,
        )?;
        check(
            "pcf_texels",
            self.pcf_texels as f64,
            1.0,
            MAX_PCF_TEXELS as f64,
        )?;
        check("ray_below_cos", self.ray_below_cos as f64, 0.0, 1.0)
    }

    /// Texels kept around the region a lookup can project to, so that the filter of a
    /// point at the edge of a spot cone or of a cube face reads texels of its own map.
    fn border_texels(&self) -> f32 {
        self.pcf_texels as f32 * 0.5 + 1.0
    }
}

/// How a map projects world points.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Projection {
    /// Looking down −Z of `view_from_world`; the map covers `|x/w|, |y/w| ≤ tan_half`.
    Perspective {
        view_from_world: Affine3A,
        tan_half: f32,
    },
    /// Looking down −Z of `view_from_world`; the map covers `|x − centre.x| ≤
    /// half_extent.x` (and y alike) in view units \[m\].
    Orthographic {
        view_from_world: Affine3A,
        centre: Vec2,
        half_extent: Vec2,
    },
}

/// Where a (normal-offset) world point lands in a map.
struct Projected {
    /// Continuous texel coordinates (texel i spans [i, i + 1)), y down.
    texel: Vec2,
    /// Depth comparable with the map's texels \[m\].
    depth: f32,
    /// World size of one texel at that depth \[m\].
    footprint: f32,
}

impl Projection {
    /// The rasterizer's viewport for this projection and the conversion from its depth
    /// attribute to the stored depth.
    fn viewport(&self, size: u32) -> (Viewport, StoredDepth) {
        match *self {
            Self::Perspective {
                view_from_world,
                tan_half,
            } => {
                let clip_from_view = Affine3A::from_mat3(Mat3::from_diagonal(Vec3::new(
                    1.0 / tan_half,
                    1.0 / tan_half,
                    -1.0,
                )));
                (
                    Viewport::perspective(size, size, clip_from_view * view_from_world),
                    StoredDepth::ViewDepth,
                )
            }
            Self::Orthographic {
                view_from_world,
                centre,
                half_extent,
            } => {
                // (x, y) to NDC, w = 1 everywhere.
                let clip_from_view = Affine3A::from_mat3_translation(
                    Mat3::from_diagonal(Vec3::new(1.0 / half_extent.x, 1.0 / half_extent.y, 0.0)),
                    Vec3::new(-centre.x / half_extent.x, -centre.y / half_extent.y, 1.0),
                );
                // Attribute = view z = −depth (larger is nearer).
                let m = view_from_world.matrix3;
                let depth_plane = Vec4::new(
                    m.x_axis.z,
                    m.y_axis.z,
                    m.z_axis.z,
                    view_from_world.translation.z,
                );
                (
                    Viewport::orthographic(
                        size,
                        size,
                        clip_from_view * view_from_world,
                        depth_plane,
                    ),
                    StoredDepth::NegatedAttribute,
                )
            }
        }
    }

    /// Where `p`, pushed `offset_texels` texel footprints along unit `normal`, lands in a
    /// `size × size` map; `None` behind a perspective view. One view transform: the
    /// offset is added in view space.
    #[inline]
    fn project_offset(
        &self,
        p: Vec3,
        normal: Vec3,
        offset_texels: f32,
        size: u32,
    ) -> Option<Projected> {
        let size = size as f32;
        let (ndc, depth, footprint) = match *self {
            Self::Perspective {
                view_from_world,
                tan_half,
            } => {
                let v = view_from_world.transform_point3(p);
                let footprint = 2.0 * tan_half * -v.z / size;
                let v = v + view_from_world.transform_vector3(normal) * (offset_texels * footprint);
                let w = -v.z;
                if w <= 0.0 || footprint <= 0.0 {
                    return None;
                }
                (Vec2::new(v.x, v.y) / (w * tan_half), w, footprint)
            }
            Self::Orthographic {
                view_from_world,
                centre,
                half_extent,
            } => {
                let footprint = 2.0 * half_extent.max_element() / size;
                let v = view_from_world.transform_point3(p)
                    + view_from_world.transform_vector3(normal) * (offset_texels * footprint);
                (
                    (Vec2::new(v.x, v.y) - centre) / half_extent,
                    -v.z,
                    footprint,
                )
            }
        };
        Some(Projected {
            texel: Vec2::new((ndc.x + 1.0) * 0.5 * size, (1.0 - ndc.y) * 0.5 * size),
            depth,
            footprint,
        })
    }
}

/// One depth image seen from a light.
#[derive(Clone, Debug)]
struct DepthMap {
    projection: Projection,
    size: u32,
    /// Row-major depths \[m\], row 0 at the top; `∞` where nothing is seen.
    depth: Vec<f32>,
    /// The geometry generation the depths were rendered at (`None`: never rendered).
    generation: Option<u64>,
}

impl DepthMap {
    /// Fraction of the filter footprint around `texel` whose stored depth is at least
    /// `depth` (lit), with bilinear weights over `k × k` texels (texels beyond the map's
    /// edge repeat the edge).
    #[inline]
    fn filtered_visibility(&self, texel: Vec2, depth: f32, k: u32) -> f32 {
        let last = self.size as i32 - 1;
        let size = self.size as usize;
        let lit = |x: i32, y: i32| {
            f32::from(u8::from(
                self.depth[y as usize * size + x as usize] >= depth,
            ))
        };
        if k <= 1 {
            let (x, y) = (floor(texel.x).clamp(0, last), floor(texel.y).clamp(0, last));
            return lit(x, y);
        }
        // k − 1 bilinear taps one texel apart centred on `texel` share one fraction f, so
        // their summed weights over the k texels per axis are [1 − f, 1, …, 1, f]/(k − 1).
        let start = texel - 0.5 - (k as f32 - 2.0) * 0.5;
        let (bx, by) = (floor(start.x), floor(start.y));
        let f = start - Vec2::new(bx as f32, by as f32);
        if k == 2 {
            // The default, bilinear: four texels, weights (1 − f, f) per axis.
            let (x0, x1) = (bx.clamp(0, last), (bx + 1).clamp(0, last));
            let (y0, y1) = (by.clamp(0, last), (by + 1).clamp(0, last));
            let top = lit(x0, y0) * (1.0 - f.x) + lit(x1, y0) * f.x;
            let bottom = lit(x0, y1) * (1.0 - f.x) + lit(x1, y1) * f.x;
            return top * (1.0 - f.y) + bottom * f.y;
        }
        let weight = |i: u32, f: f32| {
            if i == 0 {
                1.0 - f
            } else if i == k - 1 {
                f
            } else {
                1.0
            }
        };
        let mut sum = 0.0;
        for j in 0..k {
            let y = (by + j as i32).clamp(0, last);
            let mut row = 0.0;
            for i in 0..k {
                row += weight(i, f.x) * lit((bx + i as i32).clamp(0, last), y);
            }
            sum += weight(j, f.y) * row;
        }
        let norm = (k - 1) as f32;
        sum / (norm * norm)
    }
}

/// ⌊x⌋ as an integer without a libm call (x is a texel coordinate, far inside i32).
#[inline]
fn floor(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from(x < i as f32)
}

/// Which maps shade one analytic light.
#[derive(Clone, Copy, Debug)]
enum LightMaps {
    /// One map (spot, directional), index into the maps.
    Single(usize),
    /// Six faces from index `first` in the order +X, −X, +Y, −Y, +Z, −Z, around `position`.
    Cube { first: usize, position: Vec3 },
    /// No map (an empty scene): rays decide.
    None,
}

/// The six cube-face directions, in face order.
const CUBE_AXES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// The shadow maps of every analytic light of a world, rebuilt each frame into the same
/// allocations — except the maps whose view and geometry did not change since they were
/// rendered (a static light in a static scene costs nothing after its first frame).
///
/// A frame either calls [`ShadowMaps::rebuild`] (every light gets its maps), or
/// [`ShadowMaps::plan`] then [`ShadowMaps::render_planned`] with the lights that should
/// use maps this frame: the others keep their (possibly stale) depths unused, and
/// [`ShadowMaps::visibility`] answers `None` for them, so the caller casts rays.
#[derive(Clone, Debug, Default)]
pub struct ShadowMaps {
    settings: ShadowMapSettings,
    /// Per analytic light, in [`LightSet::analytic_range`](illume_transport::LightSet::analytic_range) order.
    lights: Vec<LightMaps>,
    /// Per analytic light: its maps are current and were chosen for this frame.
    active: Vec<bool>,
    maps: Vec<DepthMap>,
    /// The last plan: each map slot's view and size, and the light it belongs to.
    plan: Vec<PlannedMap>,
    /// The last plan's summary per light.
    plans: Vec<LightMapPlan>,
    /// Every instance's transform and mask at the last plan (what the depths depend on
    /// besides each map's projection; meshes never change).
    geometry: Vec<(Affine3A, u32)>,
    /// Counts the changes of `geometry` (a map rendered at an older one is stale).
    generation: u64,
    /// Maps rendered by the last build (the others were kept or unused).
    rendered: usize,
    /// Per analytic light, the cost of its maps' last rendering (see `render_cost`).
    render_cost: Vec<Option<f64>>,
}

/// One map slot of a plan.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PlannedMap {
    projection: Projection,
    size: u32,
    light: usize,
}

/// What [`ShadowMaps::plan`] found for one analytic light: the inputs of a cost model
/// choosing between its maps and shadow rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightMapPlan {
    /// Depth maps the light needs: 6 for a cube map (point lights, wide spots), 1 for a
    /// spot or directional light, 0 where no map can be made (an empty scene: rays).
    pub faces: u32,
    /// Texels in all of them.
    pub texels: u64,
    /// Its maps are up to date for the light's view and the geometry: using them costs
    /// lookups only, no rendering.
    pub current: bool,
    /// Consecutive earlier plans with the same view of the light and the same geometry
    /// (0: the light or an object moved since the last plan); `None` for a light seen
    /// for the first time.
    pub still_frames: Option<u32>,
}

impl ShadowMaps {
    /// Renders the maps of every analytic light of `world` with `settings`.
    pub fn build(world: &World, settings: &ShadowMapSettings) -> Result<Self, ShadowMapError> {
        let mut maps = Self::default();
        maps.rebuild(world, settings)?;
        Ok(maps)
    }

    /// Re-renders the maps for `world` as it is now (lights and objects may have moved),
    /// reusing this set's depth allocations, for every analytic light ([`ShadowMaps::plan`]
    /// then [`ShadowMaps::render_planned`] with all lights). Maps of different lights and
    /// faces are rendered in parallel.
    pub fn rebuild(
        &mut self,
        world: &World,
        settings: &ShadowMapSettings,
    ) -> Result<(), ShadowMapError> {
        let n = self.plan(world, settings)?.len();
        self.render_planned(world, &vec![true; n]);
        Ok(())
    }

    /// Plans this frame's maps for `world` as it is now, without rendering any: per
    /// analytic light, how many maps and texels it needs, whether its maps are current,
    /// and for how many plans its view and the geometry have stayed put. Call once per
    /// frame (the still count advances with each call), then
    /// [`ShadowMaps::render_planned`].
    pub fn plan(
        &mut self,
        world: &World,
        settings: &ShadowMapSettings,
    ) -> Result<&[LightMapPlan], ShadowMapError> {
        settings.validate()?;
        self.settings = settings.clone();
        self.lights.clear();
        let mut plan: Vec<PlannedMap> = Vec::new();
        let border = settings.border_texels();
        // Widen a view whose useful region spans `tan` so `border` texels lie outside it.
        let widened =
            |tan: f32, size: u32| tan * size as f32 / (size as f32 - 2.0 * border).max(1.0);
        let emitters = world.lights.emitters();
        for i in world.lights.analytic_range() {
            let cube = |position: Vec3, plan: &mut Vec<PlannedMap>| {
                let first = plan.len();
                let size = settings.cube_face_resolution;
                for axis in CUBE_AXES {
                    plan.push(PlannedMap {
                        projection: Projection::Perspective {
                            view_from_world: look_to(position, axis),
                            tan_half: widened(1.0, size),
                        },
                        size,
                        light: i,
                    });
                }
                LightMaps::Cube { first, position }
            };
            let entry = match &emitters[i] {
                Emitter::Point { position, .. } => cube(*position, &mut plan),
                Emitter::Spot {
                    position,
                    axis,
                    cos_outer,
                    ..
                } => {
                    let half_angle = cos_outer.clamp(-1.0, 1.0).acos();
                    if half_angle > MAX_SPOT_MAP_HALF_ANGLE_RAD {
                        cube(*position, &mut plan)
                    } else {
                        let size = settings.resolution;
                        plan.push(PlannedMap {
                            projection: Projection::Perspective {
                                view_from_world: look_to(*position, *axis),
                                tan_half: widened(half_angle.tan(), size),
                            },
                            size,
                            light: i,
                        });
                        LightMaps::Single(plan.len() - 1)
                    }
                }
                Emitter::Directional { direction, .. } => {
                    match fit_orthographic(world, *direction, settings.resolution, border) {
                        Some(projection) => {
                            plan.push(PlannedMap {
                                projection,
                                size: settings.resolution,
                                light: i,
                            });
                            LightMaps::Single(plan.len() - 1)
                        }
                        None => LightMaps::None,
                    }
                }
                Emitter::Triangle { .. } => LightMaps::None,
            };
            self.lights.push(entry);
        }
        let geometry: Vec<(Affine3A, u32)> = world
            .scene
            .instances
            .iter()
            .map(|i| (i.world_from_object, i.mask))
            .collect();
        let geometry_moved = geometry != self.geometry;
        if geometry_moved {
            self.generation += 1;
            self.geometry = geometry;
        }
        // Keep the depth allocations of the previous frame's maps.
        self.maps.truncate(plan.len());
        while self.maps.len() < plan.len() {
            self.maps.push(DepthMap {
                projection: plan[self.maps.len()].projection,
                size: 0,
                depth: Vec::new(),
                generation: None,
            });
        }
        let light_count = self.lights.len();
        let mut plans = vec![
            LightMapPlan {
                faces: 0,
                texels: 0,
                current: true,
                still_frames: None,
            };
            light_count
        ];
        for (planned, map) in plan.iter().zip(&self.maps) {
            let p = &mut plans[planned.light];
            p.faces += 1;
            p.texels += u64::from(planned.size) * u64::from(planned.size);
            p.current &= map.size == planned.size
                && map.projection == planned.projection
                && map.generation == Some(self.generation)
                && !map.depth.is_empty();
        }
        for (light, p) in plans.iter_mut().enumerate() {
            if p.faces == 0 {
                p.current = false;
            }
            // The same light (same maps, same views) in the last plan?
            let views = |plan: &[PlannedMap]| -> Vec<(Projection, u32)> {
                plan.iter()
                    .filter(|m| m.light == light)
                    .map(|m| (m.projection, m.size))
                    .collect()
            };
            p.still_frames = match self.plans.get(light) {
                Some(previous) if light_count == self.plans.len() => {
                    let same = !geometry_moved && views(&plan) == views(&self.plan);
                    Some(if same {
                        previous.still_frames.map_or(1, |k| k.saturating_add(1))
                    } else {
                        0
                    })
                }
                _ => None,
            };
        }
        if light_count != self.plans.len() {
            // Other lights: their rendering times say nothing about these.
            self.render_cost.clear();
        }
        self.plan = plan;
        self.plans = plans;
        self.active = vec![false; light_count];
        Ok(&self.plans)
    }

    /// The last [`ShadowMaps::plan`], per analytic light.
    pub fn planned(&self) -> &[LightMapPlan] {
        &self.plans
    }

    /// Renders the planned maps of the analytic lights `use_maps[i]` marks (one flag per
    /// light of the last [`ShadowMaps::plan`]; missing flags are `false`) that are not
    /// current, in parallel. Those lights' shadows then come from their maps; the others'
    /// from rays ([`ShadowMaps::visibility`] answers `None` for them).
    pub fn render_planned(&mut self, world: &World, use_maps: &[bool]) {
        let start = std::time::Instant::now();
        self.render_planned_timed(world, use_maps, &|| start.elapsed().as_secs_f64() * 1e3);
    }

    /// [`ShadowMaps::render_planned`], each light's rendering timed by `clock` (any
    /// monotonic reading: [`ShadowMaps::render_cost`] is its difference across the
    /// light's rendering, e.g. the CPU time of the threads that render).
    pub fn render_planned_timed(
        &mut self,
        world: &World,
        use_maps: &[bool],
        clock: &dyn Fn() -> f64,
    ) {
        let wanted = |light: usize| use_maps.get(light).copied().unwrap_or(false);
        for (light, active) in self.active.iter_mut().enumerate() {
            *active = wanted(light) && self.plans[light].faces > 0;
        }
        self.render_cost.resize(self.lights.len(), None);
        let scene = &world.scene;
        let generation = self.generation;
        self.rendered = 0;
        // Light by light (each light's faces and strips in parallel), so that each
        // light's rendering is timed.
        for light in 0..self.lights.len() {
            if !self.active[light] || self.plans[light].current {
                continue;
            }
            let before = clock();
            let rendered: usize = self
                .maps
                .par_iter_mut()
                .zip(&self.plan)
                .filter(|(_, planned)| planned.light == light)
                .map(|(map, planned)| {
                    if map.generation == Some(generation)
                        && map.size == planned.size
                        && map.projection == planned.projection
                        && !map.depth.is_empty()
                    {
                        return 0;
                    }
                    map.projection = planned.projection;
                    map.size = planned.size;
                    map.generation = Some(generation);
                    let (viewport, stored) = planned.projection.viewport(planned.size);
                    rasterize_depth(scene, &viewport, &mut map.depth, stored);
                    1
                })
                .sum();
            if rendered > 0 {
                self.render_cost[light] = Some(clock() - before);
            }
            self.rendered += rendered;
        }
    }

    /// Cost of the last rendering of analytic light `light`'s maps, all its faces: its
    /// wall-clock time \[ms\] after [`ShadowMaps::render_planned`], the clock's difference
    /// after [`ShadowMaps::render_planned_timed`]; `None` before its maps were first
    /// rendered.
    pub fn render_cost(&self, light: usize) -> Option<f64> {
        self.render_cost.get(light).copied().flatten()
    }

    /// Whether analytic light `light`'s shadows come from its maps this frame (the last
    /// [`ShadowMaps::render_planned`] chose it and it has maps).
    pub fn uses_maps(&self, light: usize) -> bool {
        self.active.get(light).copied().unwrap_or(false)
    }

    /// Maps the last [`ShadowMaps::rebuild`] or [`ShadowMaps::render_planned`] rendered;
    /// the others were unchanged and kept, or not used.
    pub fn rendered_last_build(&self) -> usize {
        self.rendered
    }

    /// The settings the maps were built with.
    pub fn settings(&self) -> &ShadowMapSettings {
        &self.settings
    }

    /// Number of depth maps (a cube map counts six).
    pub fn map_count(&self) -> usize {
        self.maps.len()
    }

    /// Memory held by the depth texels \[bytes\].
    pub fn memory_bytes(&self) -> usize {
        self.maps.iter().map(|m| m.depth.capacity() * 4).sum()
    }

    /// Fraction in [0, 1] of analytic light `light` (an index of
    /// [`LightSet::analytic_range`](illume_transport::LightSet::analytic_range)) that reaches `hit`
    /// along `sample` (which came from that light): filtered, biased depth comparisons
    /// standing in for [`World::unoccluded`]. `None` when the light has no map, or lights
    /// the point at a grazing angle ([`ShadowMapSettings::ray_below_cos`]) and the map
    /// does not find it fully shadowed: the caller casts a ray.
    pub fn visibility(&self, light: usize, hit: &SurfaceHit, sample: &LightSample) -> Option<f32> {
        if !self.uses_maps(light) {
            return None;
        }
        let map = match *self.lights.get(light)? {
            LightMaps::None => return None,
            LightMaps::Single(m) => &self.maps[m],
            LightMaps::Cube { first, position } => {
                let d = hit.position - position;
                let a = d.abs();
                let face = if a.x >= a.y && a.x >= a.z {
                    usize::from(d.x < 0.0)
                } else if a.y >= a.z {
                    2 + usize::from(d.y < 0.0)
                } else {
                    4 + usize::from(d.z < 0.0)
                };
                &self.maps[first + face]
            }
        };
        let s = &self.settings;
        let n = hit.facing_geometric_normal();
        let cos = n.dot(sample.wi).clamp(1e-4, 1.0);
        let grazing = cos < s.ray_below_cos;
        let tan = ((1.0 - cos * cos).sqrt() / cos).min(MAX_SLOPE);
        // A point behind a perspective view cannot be lit by it (it is outside its cone
        // or face); treat it as lit and let the light's own falloff decide.
        let Some(at) =
            map.projection
                .project_offset(hit.position, n, s.normal_offset_texels, map.size)
        else {
            return Some(1.0);
        };
        let bias = at.footprint * (s.depth_bias_texels + s.slope_bias_texels * tan);
        let v = map.filtered_visibility(at.texel, at.depth - bias, s.pcf_texels);
        if grazing && v > 0.0 {
            // Grazing light: the map's texel and bias are too coarse to say "lit" here
            // (they let light past mouldings and arches); its "shadowed" stands.
            return None;
        }
        Some(v)
    }
}

/// World-to-view transform of a view at `eye` looking along unit `forward` (down −Z).
fn look_to(eye: Vec3, forward: Vec3) -> Affine3A {
    // Any up not parallel to the axis; the maps are square, so its roll does not matter.
    let up = if forward.y.abs() < 0.9 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    Affine3A::look_to_rh(eye, forward, up)
}

/// The orthographic view along `direction` just enclosing the scene's bounding box, with
/// `border` texels of margin on each side; `None` for an empty scene.
fn fit_orthographic(world: &World, direction: Vec3, size: u32, border: f32) -> Option<Projection> {
    let bounds = world.scene.bounds();
    if bounds.is_empty() {
        return None;
    }
    let view_from_world = look_to(bounds.center(), direction);
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for corner in bounds.corners() {
        let v = view_from_world.transform_point3(corner);
        lo = lo.min(Vec2::new(v.x, v.y));
        hi = hi.max(Vec2::new(v.x, v.y));
    }
    // A scene flat in one view axis still needs a non-zero extent.
    let floor = 1e-4 * (bounds.max - bounds.min).length().max(1e-3);
    let half = ((hi - lo) * 0.5).max(Vec2::splat(floor));
    let half_extent = half * size as f32 / (size as f32 - 2.0 * border).max(1.0);
    Some(Projection::Orthographic {
        view_from_world,
        centre: (lo + hi) * 0.5,
        half_extent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16 × 16 map whose texels left of column 8 hold an occluder at depth 1.
    fn half_shadowed() -> DepthMap {
        let size = 16;
        let depth = (0..size * size)
            .map(|i| if i % size < 8 { 1.0 } else { f32::INFINITY })
            .collect();
        DepthMap {
            projection: Projection::Perspective {
                view_from_world: Affine3A::IDENTITY,
                tan_half: 1.0,
            },
            size: size as u32,
            depth,
            generation: None,
        }
    }

    #[test]
    fn filters_weigh_texel_comparisons_bilinearly() {
        let map = half_shadowed();
        let at = |x: f32, k: u32| map.filtered_visibility(Vec2::new(x, 5.3), 2.0, k);
        // Nearest texel: hard edge at x = 8.
        assert_eq!((at(7.99, 1), at(8.0, 1)), (0.0, 1.0));
        // Bilinear: texel centres are exact, the boundary between them is half lit.
        assert_eq!((at(7.5, 2), at(8.5, 2)), (0.0, 1.0));
        assert!((at(8.0, 2) - 0.5).abs() < 1e-6);
        assert!((at(8.25, 2) - 0.75).abs() < 1e-6);
        // 3 × 3: two bilinear taps a texel apart, so the ramp is twice as wide.
        assert!((at(8.0, 3) - 0.5).abs() < 1e-6);
        assert_eq!((at(7.0, 3), at(9.0, 3)), (0.0, 1.0));
        assert!((at(8.5, 3) - 0.75).abs() < 1e-6);
        // In front of the occluder everything is lit; beyond the map's edge the edge
        // texel repeats.
        assert_eq!(map.filtered_visibility(Vec2::new(3.0, 5.0), 0.5, 3), 1.0);
        assert_eq!(map.filtered_visibility(Vec2::new(-4.0, 5.0), 2.0, 2), 0.0);
        assert_eq!(map.filtered_visibility(Vec2::new(40.0, 5.0), 2.0, 2), 1.0);
    }

    #[test]
    fn settings_out_of_range_are_rejected_by_name() {
        assert_eq!(ShadowMapSettings::default().validate(), Ok(()));
        for (settings, field) in [
            (
                ShadowMapSettings {
                    resolution: 0,
                    ..Default::default()
                },
                "resolution",
            ),
            (
                ShadowMapSettings {
                    cube_face_resolution: MAX_RESOLUTION + 1,
                    ..Default::default()
                },
                "cube_face_resolution",
            ),
            (
                ShadowMapSettings {
                    slope_bias_texels: f32::NAN,
                    ..Default::default()
                },
                "slope_bias_texels",
            ),
            (
                ShadowMapSettings {
                    pcf_texels: 0,
                    ..Default::default()
                },
                "pcf_texels",
            ),
            (
                ShadowMapSettings {
                    ray_below_cos: 1.5,
                    ..Default::default()
                },
                "ray_below_cos",
            ),
            (
                ShadowMapSettings {
                    ray_below_cos: f32::NAN,
                    ..Default::default()
                },
                "ray_below_cos",
            ),
        ] {
            match settings.validate() {
                Err(ShadowMapError::OutOfRange { field: f, .. }) => assert_eq!(f, field),
                other => panic!("{field}: {other:?}"),
            }
        }
    }

    #[test]
    fn rebuilds_reuse_the_depth_allocations() {
        let mut world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
        let settings = ShadowMapSettings {
            resolution: 64,
            ..Default::default()
        };
        let mut maps = ShadowMaps::build(&world, &settings).expect("valid");
        assert_eq!(maps.map_count(), 1, "one spot light, one map");
        let address = maps.maps[0].depth.as_ptr();
        let before = maps.maps[0].depth.clone();
        world.set_time(1.0); // the light moves
        maps.rebuild(&world, &settings).expect("valid");
        assert_eq!(maps.maps[0].depth.as_ptr(), address);
        assert_ne!(maps.maps[0].depth, before, "the map follows the light");
        assert_eq!(maps.memory_bytes(), 64 * 64 * 4);
    }

    #[test]
    fn unchanged_maps_are_kept_and_changed_ones_rerendered() {
        let mut world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
        let settings = ShadowMapSettings {
            resolution: 64,
            ..Default::default()
        };
        let mut maps = ShadowMaps::build(&world, &settings).expect("valid");
        assert_eq!(maps.rendered_last_build(), 1);
        maps.rebuild(&world, &settings).expect("valid");
        assert_eq!(
            maps.rendered_last_build(),
            0,
            "nothing moved: the map is kept"
        );
        // An instance moves (the light does not): the map is re-rendered and equals a
        // fresh one.
        let moved = world
            .apply_edit(&illume_scene::Edit::SetInstanceTransform {
                instance: illume_scene::InstanceId(2),
                world_from_object: Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.05))
                    * world.scene.instances[2].world_from_object,
            })
            .expect("edit");
        assert!(!moved.is_empty());
        maps.rebuild(&world, &settings).expect("valid");
        assert_eq!(maps.rendered_last_build(), 1, "geometry moved");
        let fresh = ShadowMaps::build(&world, &settings).expect("valid");
        assert_eq!(maps.maps[0].depth, fresh.maps[0].depth);
        // A bias change alone keeps the depths (bias applies at lookup).
        let biased = ShadowMapSettings {
            depth_bias_texels: 2.0,
            ..settings
        };
        maps.rebuild(&world, &biased).expect("valid");
        assert_eq!(maps.rendered_last_build(), 0);
    }

    #[test]
    fn planned_maps_render_only_for_chosen_lights_and_go_stale_while_unused() {
        let mut world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
        let settings = ShadowMapSettings {
            resolution: 64,
            ..Default::default()
        };
        let mut maps = ShadowMaps::default();
        let first = maps.plan(&world, &settings).expect("valid")[0];
        assert_eq!(
            first,
            LightMapPlan {
                faces: 1,
                texels: 64 * 64,
                current: false,
                still_frames: None,
            }
        );
        // Rays this frame: nothing rendered, no map used.
        maps.render_planned(&world, &[false]);
        assert_eq!((maps.rendered_last_build(), maps.uses_maps(0)), (0, false));
        assert_eq!(maps.render_cost(0), None);
        let second = maps.plan(&world, &settings).expect("valid")[0];
        assert_eq!((second.current, second.still_frames), (false, Some(1)));
        maps.render_planned(&world, &[true]);
        assert_eq!((maps.rendered_last_build(), maps.uses_maps(0)), (1, true));
        assert!(maps.render_cost(0).is_some());
        assert!(maps.plan(&world, &settings).expect("valid")[0].current);
        maps.render_planned(&world, &[true]);
        assert_eq!(maps.rendered_last_build(), 0, "a current map is kept");
        // An object moves while the light uses rays; when maps are chosen again, the
        // map (same view, older geometry) is re-rendered.
        world
            .apply_edit(&illume_scene::Edit::SetInstanceTransform {
                instance: illume_scene::InstanceId(2),
                world_from_object: Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.05))
                    * world.scene.instances[2].world_from_object,
            })
            .expect("edit");
        let moved = maps.plan(&world, &settings).expect("valid")[0];
        assert_eq!((moved.current, moved.still_frames), (false, Some(0)));
        maps.render_planned(&world, &[false]);
        let later = maps.plan(&world, &settings).expect("valid")[0];
        assert_eq!((later.current, later.still_frames), (false, Some(1)));
        maps.render_planned(&world, &[true]);
        assert_eq!(maps.rendered_last_build(), 1);
        let fresh = ShadowMaps::build(&world, &settings).expect("valid");
        assert_eq!(maps.maps[0].depth, fresh.maps[0].depth);
    }

    #[test]
    fn a_directional_map_stores_the_distance_along_the_light() {
        // cornell-spot's geometry under a sun straight down: the floor (y = 0) is seen
        // wherever the boxes and the sphere do not cover it, at depth centre.y − 0 below
        // the plane through the scene centre; nothing is nearer than the ceiling.
        let mut scene = illume_scene::builtin::load("cornell-spot").expect("builtin");
        scene.lights[0].kind = illume_scene::LightKind::Directional {
            irradiance: illume_core::Rgb::ONE,
        };
        // The spot's node points along −Z rotated about x; straight down instead.
        scene.lights[0].world_from_light = Affine3A::from_rotation_x(-std::f32::consts::FRAC_PI_2);
        let world = World::new(scene);
        let maps = ShadowMaps::build(&world, &ShadowMapSettings::default()).expect("valid");
        let centre_y = world.scene.bounds().center().y;
        let map = &maps.maps[0];
        let (lo, hi) = map
            .depth
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &d| {
                (lo.min(d), hi.max(d))
            });
        // The open box seen from above: the ceiling's top at depth centre.y − 2 is
        // nearest; the far end of the map is the border (nothing), stored as ∞.
        assert!((lo - (centre_y - 2.0)).abs() < 1e-4, "nearest {lo}");
        assert_eq!(hi, f32::INFINITY);
    }
}
