//! The GPU side of the window: the surface, the frame's texture, the pass that draws it
//! (`display.wgsl`) and egui's pass.
//!
//! The frame is tone-mapped on the CPU by PNG output's own code ([`display_bytes`]: the
//! bytes of `to_srgb8`), once per new frame or tone change, and uploaded as 8-bit RGBA:
//! the window shows exactly the bytes a PNG would hold, a quarter of the float upload,
//! and a redraw without a new frame does no per-pixel work beyond a texel copy.

use crate::ViewError;
use illume_core::image::{RgbImage, ToneMap, srgb8};
use rayon::prelude::*;
use std::sync::Arc;
use winit::window::Window;

/// The display shader's uniforms (mirrors `Params` in `display.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    size: [u32; 2],
    pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<Params>() == 16);

/// Surface, device and the two passes.
pub struct Gpu {
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    frame: Option<(wgpu::Texture, wgpu::BindGroup, u32, u32)>,
    /// egui's renderer.
    pub egui: egui_wgpu::Renderer,
    /// The adapter's name and backend, for logs.
    pub adapter: String,
}

/// Times of one [`Gpu::draw`] \[ms\].
#[derive(Clone, Copy, Debug, Default)]
pub struct DrawTimes {
    /// Waiting for the surface's next image.
    pub acquire_ms: f64,
    /// Recording and running the tone map and egui passes (run to completion only when
    /// measured, see [`Gpu::draw`]).
    pub render_ms: f64,
    /// Handing the image to the window system.
    pub present_ms: f64,
}

/// Where the frame is drawn.
pub struct Viewport {
    /// Physical pixels: x, y, width, height.
    pub rect: [f32; 4],
}

/// The display bytes of `image` (8-bit sRGB RGBA, row-major) into `out`: for each pixel
/// the bytes `illume_core::image::to_srgb8` writes to a PNG, alpha 255. Rows in
/// parallel.
pub fn display_bytes(image: &RgbImage, tone: &ToneMap, out: &mut Vec<u8>) {
    let n = image.pixels().len();
    out.resize(n * 4, 255);
    let tone = tone.prepared();
    let convert = |o: &mut [u8], px: &[illume_core::Rgb]| {
        for (o, &p) in o.chunks_exact_mut(4).zip(px) {
            let d = tone.apply(p);
            o[0] = srgb8(d.x);
            o[1] = srgb8(d.y);
            o[2] = srgb8(d.z);
            o[3] = 255;
        }
    };
    // A small frame on the window's thread: waiting for rayon's workers on a loaded
    // machine costs more than the conversion.
    if n < PARALLEL_PIXELS {
        convert(out, image.pixels());
        return;
    }
    let row = image.width().max(1) as usize;
    out.par_chunks_mut(row * 4)
        .zip(image.pixels().par_chunks(row))
        .for_each(|(o, px)| convert(o, px));
}

/// Frames of at least this many pixels are converted in parallel rows.
const PARALLEL_PIXELS: usize = 1 << 16;

impl Gpu {
    /// Creates the surface of `window` on the first adapter that can present to it
    /// (Vulkan, then GL; `WGPU_BACKEND` overrides). The backends are tried one at a
    /// time: probing GL when Vulkan works starts EGL, whose drivers print errors
    /// ("DRI2: failed to load driver", "XDG_RUNTIME_DIR is invalid") on a normal start.
    pub fn new(window: Arc<Window>) -> Result<Self, ViewError> {
        let tries = match wgpu::Backends::from_env() {
            Some(b) => vec![b],
            None => vec![wgpu::Backends::VULKAN, wgpu::Backends::GL],
        };
        let mut errors = Vec::new();
        let mut found = None;
        for backends in tries {
            let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
                backends,
                ..wgpu::InstanceDescriptor::new_without_display_handle()
            });
            let surface = match instance.create_surface(window.clone()) {
                Ok(s) => s,
                Err(e) => {
                    errors.push(format!("{backends:?}: cannot create a surface: {e}"));
                    continue;
                }
            };
            match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::default(),
                force_fallback_adapter: false,
                compatible_surface: Some(&surface),
                apply_limit_buckets: false,
            })) {
                Ok(adapter) => {
                    found = Some((surface, adapter));
                    break;
                }
                Err(e) => errors.push(format!("{backends:?}: {e}")),
            }
        }
        let (surface, adapter) = found.ok_or_else(|| {
            ViewError::Gpu(format!(
                "no Vulkan or GL adapter can present to the window ({}); on Debian install mesa-vulkan-drivers and libvulkan1 (scripts/ci/install-viewer-deps.sh)",
                errors.join("; ")
            ))
        })?;
        let info = adapter.get_info();
        let adapter_name = format!("{} ({:?})", info.name, info.backend);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("illume view"),
            required_limits:
                wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| ViewError::Gpu(format!("{adapter_name}: cannot open the device: {e}")))?;
        let caps = surface.get_capabilities(&adapter);
        // A non-sRGB format: the shader encodes sRGB itself, exactly as PNG output does.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| ViewError::Gpu(format!("{adapter_name}: the surface has no format")))?;
        let size = window.inner_size();
        // Never block the window's thread on a vertical blank it does not need: the window
        // paces itself (one redraw per refresh at most).
        let present_mode = [wgpu::PresentMode::Immediate, wgpu::PresentMode::Mailbox]
            .into_iter()
            .find(|m| caps.present_modes.contains(m))
            .unwrap_or(wgpu::PresentMode::Fifo);
        let adapter_name = format!(
            "{adapter_name}, present mode {present_mode:?} of {:?}",
            caps.present_modes
        );
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&device, &config);
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("tonemap"),
            source: wgpu::ShaderSource::Wgsl(include_str!("display.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tonemap"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("tonemap"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("tonemap"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            multiview_mask: None,
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tonemap params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let egui = egui_wgpu::Renderer::new(
            &device,
            format,
            egui_wgpu::RendererOptions {
                dithering: false,
                ..Default::default()
            },
        );
        Ok(Self {
            surface,
            device,
            queue,
            config,
            pipeline,
            layout,
            params,
            frame: None,
            egui,
            adapter: adapter_name,
        })
    }

    /// Follows a window resize.
    pub fn resize(&mut self, width: u32, height: u32) {
        if width > 0 && height > 0 {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.device, &self.config);
        }
    }

    /// Uploads a frame's display bytes (8-bit RGBA, `w × h`, from [`display_bytes`]).
    pub fn upload(&mut self, rgba: &[u8], w: u32, h: u32) {
        if !matches!(&self.frame, Some((_, _, fw, fh)) if *fw == w && *fh == h) {
            let texture = self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("hdr frame"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let view = texture.create_view(&Default::default());
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("tonemap"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: self.params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                ],
            });
            self.frame = Some((texture, bind, w, h));
            let params = Params {
                size: [w, h],
                pad: [0; 2],
            };
            self.queue
                .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        }
        if let Some((texture, _, _, _)) = &self.frame {
            self.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                rgba,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(w * 4),
                    rows_per_image: Some(h),
                },
                wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
            );
        }
    }

    /// Draws the frame into `viewport` and egui's shapes over everything; presents.
    pub fn draw(
        &mut self,
        viewport: &Viewport,
        paint: &[egui::ClippedPrimitive],
        textures: &mut egui::TexturesDelta,
        pixels_per_point: f32,
        measure: bool,
    ) -> Result<DrawTimes, ViewError> {
        let mut times = DrawTimes::default();
        let t0 = std::time::Instant::now();
        for (id, deltas) in textures.set.drain() {
            for delta in deltas {
                self.egui
                    .update_texture(&self.device, &self.queue, id, &delta);
            }
        }
        let frees: Vec<egui::TextureId> = textures.free.drain().collect();
        let surface_texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                for id in &frees {
                    self.egui.free_texture(id);
                }
                return Ok(times);
            }
            _ => {
                for id in &frees {
                    self.egui.free_texture(id);
                }
                return Ok(times);
            }
        };
        let t1 = std::time::Instant::now();
        times.acquire_ms = (t1 - t0).as_secs_f64() * 1e3;
        let target = surface_texture.texture.create_view(&Default::default());
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point,
        };
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let extra =
            self.egui
                .update_buffers(&self.device, &self.queue, &mut encoder, paint, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("frame + egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &target,
                        resolve_target: None,
                        depth_slice: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: 0.02,
                                g: 0.02,
                                b: 0.02,
                                a: 1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            let [x, y, w, h] = viewport.rect;
            let (sw, sh) = (self.config.width as f32, self.config.height as f32);
            let x0 = x.clamp(0.0, sw - 1.0);
            let y0 = y.clamp(0.0, sh - 1.0);
            let w = w.min(sw - x0);
            let h = h.min(sh - y0);
            if let Some((_, bind, _, _)) = &self.frame
                && w >= 1.0
                && h >= 1.0
            {
                pass.set_viewport(x0, y0, w, h, 0.0, 1.0);
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, bind, &[]);
                pass.draw(0..3, 0..1);
                pass.set_viewport(0.0, 0.0, sw, sh, 0.0, 1.0);
            }
            self.egui.render(&mut pass, paint, &screen);
        }
        self.queue
            .submit(extra.into_iter().chain(std::iter::once(encoder.finish())));
        if measure {
            // Wait for the passes to finish so that their time is measured, not queued.
            let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        }
        let t2 = std::time::Instant::now();
        times.render_ms = (t2 - t1).as_secs_f64() * 1e3;
        self.queue.present(surface_texture);
        times.present_ms = t2.elapsed().as_secs_f64() * 1e3;
        for id in &frees {
            self.egui.free_texture(id);
        }
        Ok(times)
    }

    /// The largest texture side the device takes (for egui).
    pub fn max_texture_side(&self) -> usize {
        self.device.limits().max_texture_dimension_2d as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::image::{ToneCurve, to_srgb8};

    /// The window's bytes are PNG output's bytes, for every curve and exposure, on the
    /// window's thread (small frames) and in parallel rows (large ones).
    #[test]
    fn display_bytes_are_the_png_bytes() {
        const { assert!(37 * 23 < PARALLEL_PIXELS && 300 * 250 >= PARALLEL_PIXELS) };
        for (w, h) in [(37, 23), (300, 250)] {
            check_display_bytes(w, h);
        }
    }

    fn check_display_bytes(w: u32, h: u32) {
        let mut image = RgbImage::filled(w, h, illume_core::Rgb::ZERO);
        let mut state = 12345u32;
        for p in image.pixels_mut() {
            let mut next = || {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                // Radiances over 8 decades, a few negative and zero.
                let u = (state >> 8) as f32 / (1 << 24) as f32;
                if u < 0.02 {
                    -u
                } else {
                    10f32.powf(u * 8.0 - 5.0)
                }
            };
            *p = illume_core::Rgb::new(next(), next(), next());
        }
        let mut out = Vec::new();
        for curve in [ToneCurve::Aces, ToneCurve::Reinhard, ToneCurve::Clamp] {
            for exposure_ev in [-3.3, 0.0, 1.7] {
                let tone = ToneMap { exposure_ev, curve };
                display_bytes(&image, &tone, &mut out);
                let png = to_srgb8(&image, &tone);
                assert_eq!(out.len(), png.len() / 3 * 4);
                for (i, (d, p)) in out.chunks_exact(4).zip(png.chunks_exact(3)).enumerate() {
                    assert_eq!(&d[..3], p, "pixel {i}, {tone:?}");
                    assert_eq!(d[3], 255);
                }
            }
        }
    }
}
