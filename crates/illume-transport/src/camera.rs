//! Primary rays of the scene's perspective camera.

use illume_core::{Affine3A, Ray, Vec2, Vec3};
use illume_scene::Camera;

/// Generates primary rays for a `width × height` image: pixel (x, y) with y = 0 at the
/// top; the vertical field of view is the camera's, the aspect the image's.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    world_from_camera: Affine3A,
    origin: Vec3,
    tan_half_y: f32,
    aspect: f32,
    width: u32,
    height: u32,
    /// Where [`CameraRays::row`] samples each pixel (0.5, 0.5 = the centre).
    offset: Vec2,
}

impl CameraRays {
    /// Ray generator for `camera` at its current transform.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        Self {
            world_from_camera: camera.world_from_camera,
            origin: camera.world_from_camera.translation.into(),
            tan_half_y: (camera.yfov_rad * 0.5).tan(),
            aspect: width as f32 / height.max(1) as f32,
            width,
            height,
            offset: Vec2::splat(0.5),
        }
    }

    /// These rays with [`CameraRays::row`] sampling each pixel at `offset` in `[0, 1)²`
    /// instead of its centre (jittered frames).
    pub fn with_offset(self, offset: Vec2) -> Self {
        Self { offset, ..self }
    }

    /// Where [`CameraRays::row`] samples each pixel (0.5, 0.5 = the centre).
    pub fn offset(&self) -> Vec2 {
        self.offset
    }

    /// The unit-direction ray through image position `(x + offset.x, y + offset.y)`,
    /// `offset` in `[0, 1)²` within the pixel (0.5, 0.5 = centre).
    #[inline]
    pub fn ray(&self, x: u32, y: u32, offset: Vec2) -> Ray {
        let ndc_x = ((x as f32 + offset.x) / self.width as f32) * 2.0 - 1.0;
        let ndc_y = 1.0 - ((y as f32 + offset.y) / self.height as f32) * 2.0;
        let d = Vec3::new(
            ndc_x * self.tan_half_y * self.aspect,
            ndc_y * self.tan_half_y,
            -1.0,
        );
        let dir = self.world_from_camera.transform_vector3(d).normalize();
        Ray::new(self.origin, dir)
    }

    /// The rays of image row `y` through each pixel's sample point (its centre unless
    /// [`CameraRays::with_offset`]), generated incrementally along the row (the same
    /// directions as [`CameraRays::ray`] with that offset up to f32 rounding).
    #[inline]
    pub fn row(&self, y: u32) -> RowRays {
        let ndc_y = 1.0 - ((y as f32 + self.offset.y) / self.height as f32) * 2.0;
        let sx = 2.0 / self.width as f32 * self.tan_half_y * self.aspect;
        let first = Vec3::new(
            (2.0 * self.offset.x / self.width as f32 - 1.0) * self.tan_half_y * self.aspect,
            ndc_y * self.tan_half_y,
            -1.0,
        );
        RowRays {
            origin: self.origin,
            first: self.world_from_camera.transform_vector3(first),
            step: self
                .world_from_camera
                .transform_vector3(Vec3::new(sx, 0.0, 0.0)),
        }
    }

    /// The change of the unnormalised centre direction ([`RowRays::direction`]) from one
    /// image row to the next (downwards).
    #[inline]
    pub fn row_step(&self) -> Vec3 {
        let sy = -2.0 / self.height as f32 * self.tan_half_y;
        self.world_from_camera
            .transform_vector3(Vec3::new(0.0, sy, 0.0))
    }

    /// The camera position.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
}

/// Centre rays of one image row (see [`CameraRays::row`]).
#[derive(Clone, Copy, Debug)]
pub struct RowRays {
    origin: Vec3,
    /// Unnormalised direction through the centre of pixel 0.
    first: Vec3,
    /// Change of the unnormalised direction per pixel.
    step: Vec3,
}

impl RowRays {
    /// The unit-direction ray through the centre of pixel `x` of the row.
    #[inline]
    pub fn ray(&self, x: u32) -> Ray {
        Ray::new(self.origin, self.direction(x).normalize())
    }

    /// The change of [`RowRays::direction`] from one pixel to the next (rightwards).
    #[inline]
    pub fn step(&self) -> Vec3 {
        self.step
    }

    /// The unnormalised direction through the centre of pixel `x` of the row (its
    /// length grows away from the image centre).
    #[inline]
    pub fn direction(&self, x: u32) -> Vec3 {
        self.first + self.step * x as f32
    }
}
