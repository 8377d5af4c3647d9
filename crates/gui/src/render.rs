//! The viewport's GPU side: an `egui_wgpu` paint callback (the pattern of
//! egui's `custom3d_wgpu` demo). The scene is drawn into an off-screen
//! colour + depth target in `prepare` (egui's own pass has no depth buffer,
//! and the test renderer none either) and copied into egui's pass in
//! `paint`. Geometry buffers are created once per scene generation; a frame
//! writes only the uniforms (and the object colours when they changed).

use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu::{self, wgpu};
use wgpu::util::DeviceExt as _;

use crate::scene::{LineVertex, MeshVertex, Scene};

const STYLE_W: u32 = 1024;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Uniforms {
    pub view_proj: [[f32; 4]; 4],
    pub light: [f32; 4],
    pub section: [f32; 4],
    pub flags: [f32; 4],
}

/// What one frame asks the GPU to draw; cheap to make (Arcs and a few numbers).
pub struct ViewportCallback {
    pub scene: Arc<Scene>,
    pub style: Arc<Vec<[u8; 4]>>,
    pub style_generation: u64,
    pub uniforms: Uniforms,
    pub size_px: [u32; 2],
    /// The part drawn solid (writes depth) or as a ghost.
    pub part_solid: bool,
    pub background: [f32; 3],
}

struct GpuGeometry {
    generation: u64,
    vertices: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    lines: Option<wgpu::Buffer>,
    line_count: u32,
    part: std::ops::Range<u32>,
    features: std::ops::Range<u32>,
}

struct Offscreen {
    size: [u32; 2],
    color: wgpu::TextureView,
    depth: wgpu::TextureView,
    blit: wgpu::BindGroup,
}

/// Lives in egui_wgpu's callback resources for the life of the renderer.
pub struct ViewportGpu {
    target_format: wgpu::TextureFormat,
    solid: wgpu::RenderPipeline,
    ghost: wgpu::RenderPipeline,
    lines: wgpu::RenderPipeline,
    blit: wgpu::RenderPipeline,
    scene_layout: wgpu::BindGroupLayout,
    blit_layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    sampler: wgpu::Sampler,
    geometry: Option<GpuGeometry>,
    style: Option<(u64, u32, wgpu::Texture, wgpu::BindGroup)>,
    offscreen: Option<Offscreen>,
}

/// Installs the pipelines; call once with the app's render state.
pub fn install(rs: &egui_wgpu::RenderState) {
    let gpu = ViewportGpu::new(&rs.device, rs.target_format);
    rs.renderer.write().callback_resources.insert(gpu);
}

impl ViewportGpu {
    fn new(device: &wgpu::Device, target_format: wgpu::TextureFormat) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("thinplan scene"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let blit_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("thinplan blit"),
            source: wgpu::ShaderSource::Wgsl(include_str!("blit.wgsl").into()),
        });
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("thinplan scene"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let blit_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("thinplan blit"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let scene_pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("thinplan scene"),
            bind_group_layouts: &[Some(&scene_layout)],
            immediate_size: 0,
        });
        let blit_pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("thinplan blit"),
            bind_group_layouts: &[Some(&blit_layout)],
            immediate_size: 0,
        });
        let mesh_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Uint32];
        let line_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Unorm8x4, 2 => Uint32];
        let pipeline = |label: &str,
                        vs: &str,
                        fs: &str,
                        stride: usize,
                        attrs: &[wgpu::VertexAttribute],
                        topology: wgpu::PrimitiveTopology,
                        depth_write: bool,
                        bias: i32| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&scene_pl),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(vs),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: stride as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: attrs,
                    })],
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                },
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fs),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: target_format,
                        blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                }),
                primitive: wgpu::PrimitiveState {
                    topology,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState {
                        constant: bias,
                        slope_scale: if bias != 0 { -1.0 } else { 0.0 },
                        clamp: 0.0,
                    },
                }),
                multisample: wgpu::MultisampleState::default(),
                multiview_mask: None,
                cache: None,
            })
        };
        let ms = std::mem::size_of::<MeshVertex>();
        let ls = std::mem::size_of::<LineVertex>();
        let tri = wgpu::PrimitiveTopology::TriangleList;
        let solid = pipeline("solid", "vs_mesh", "fs_mesh", ms, &mesh_attrs, tri, true, 0);
        let ghost = pipeline(
            "ghost",
            "vs_mesh",
            "fs_mesh",
            ms,
            &mesh_attrs,
            tri,
            false,
            -2,
        );
        let lines = pipeline(
            "lines",
            "vs_line",
            "fs_line",
            ls,
            &line_attrs,
            wgpu::PrimitiveTopology::LineList,
            true,
            0,
        );
        let blit = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("thinplan blit"),
            layout: Some(&blit_pl),
            vertex: wgpu::VertexState {
                module: &blit_shader,
                entry_point: Some("vs_blit"),
                buffers: &[],
                compilation_options: wgpu::PipelineCompilationOptions::default(),
            },
            fragment: Some(wgpu::FragmentState {
                module: &blit_shader,
                entry_point: Some("fs_blit"),
                targets: &[Some(target_format.into())],
                compilation_options: wgpu::PipelineCompilationOptions::default(),
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            multiview_mask: None,
            cache: None,
        });
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("thinplan uniforms"),
            contents: bytemuck::bytes_of(&Uniforms::default()),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::UNIFORM,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("thinplan blit"),
            ..Default::default()
        });
        ViewportGpu {
            target_format,
            solid,
            ghost,
            lines,
            blit,
            scene_layout,
            blit_layout,
            uniforms,
            sampler,
            geometry: None,
            style: None,
            offscreen: None,
        }
    }

    fn upload_geometry(&mut self, device: &wgpu::Device, scene: &Scene) {
        let buf = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
            (!bytes.is_empty()).then(|| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytes,
                    usage,
                })
            })
        };
        self.geometry = Some(GpuGeometry {
            generation: scene.generation,
            vertices: buf(
                "vertices",
                bytemuck::cast_slice(&scene.vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: buf(
                "indices",
                bytemuck::cast_slice(&scene.indices),
                wgpu::BufferUsages::INDEX,
            ),
            lines: buf(
                "lines",
                bytemuck::cast_slice(&scene.lines),
                wgpu::BufferUsages::VERTEX,
            ),
            line_count: scene.lines.len() as u32,
            part: scene.part_indices.clone(),
            features: scene.feature_indices.clone(),
        });
    }

    fn upload_style(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, cb: &ViewportCallback) {
        let rows = (cb.style.len() as u32).div_ceil(STYLE_W).max(1);
        let fits = matches!(&self.style, Some((_, r, _, _)) if *r >= rows);
        if !fits {
            let tex = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("thinplan object colours"),
                size: wgpu::Extent3d {
                    width: STYLE_W,
                    height: rows,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let view = tex.create_view(&wgpu::TextureViewDescriptor::default());
            let bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("thinplan scene"),
                layout: &self.scene_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: self.uniforms.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                ],
            });
            self.style = Some((0, rows, tex, bg));
        }
        let Some((gen, rows, tex, _)) = &mut self.style else {
            return;
        };
        if *gen == cb.style_generation && fits {
            return;
        }
        let mut data = vec![0u8; (STYLE_W * *rows * 4) as usize];
        for (i, c) in cb.style.iter().enumerate() {
            data[i * 4..i * 4 + 4].copy_from_slice(c);
        }
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: tex,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(STYLE_W * 4),
                rows_per_image: Some(*rows),
            },
            wgpu::Extent3d {
                width: STYLE_W,
                height: *rows,
                depth_or_array_layers: 1,
            },
        );
        *gen = cb.style_generation;
    }

    fn ensure_offscreen(&mut self, device: &wgpu::Device, size: [u32; 2]) {
        if self.offscreen.as_ref().is_some_and(|o| o.size == size) {
            return;
        }
        let tex = |label: &str, format, usage| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size[0],
                        height: size[1],
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        let color = tex(
            "thinplan viewport colour",
            self.target_format,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let depth = tex(
            "thinplan viewport depth",
            DEPTH,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let blit = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("thinplan blit"),
            layout: &self.blit_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&color),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        });
        self.offscreen = Some(Offscreen {
            size,
            color,
            depth,
            blit,
        });
    }

    fn draw(&self, encoder: &mut wgpu::CommandEncoder, cb: &ViewportCallback) {
        let (Some(off), Some((_, _, _, bg)), Some(g)) =
            (&self.offscreen, &self.style, &self.geometry)
        else {
            return;
        };
        let srgb = self.target_format.is_srgb();
        let lin = |c: f32| if srgb { (c as f64).powf(2.2) } else { c as f64 };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("thinplan viewport"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &off.color,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: lin(cb.background[0]),
                        g: lin(cb.background[1]),
                        b: lin(cb.background[2]),
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
                depth_slice: None,
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &off.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, bg, &[]);
        if let (Some(v), Some(i)) = (&g.vertices, &g.indices) {
            pass.set_vertex_buffer(0, v.slice(..));
            pass.set_index_buffer(i.slice(..), wgpu::IndexFormat::Uint32);
            if !g.part.is_empty() {
                pass.set_pipeline(if cb.part_solid {
                    &self.solid
                } else {
                    &self.ghost
                });
                pass.draw_indexed(g.part.clone(), 0, 0..1);
            }
        }
        if let Some(l) = &g.lines {
            pass.set_pipeline(&self.lines);
            pass.set_vertex_buffer(0, l.slice(..));
            pass.draw(0..g.line_count, 0..1);
        }
        if let (Some(v), Some(i)) = (&g.vertices, &g.indices) {
            if !g.features.is_empty() {
                pass.set_pipeline(&self.ghost);
                pass.set_vertex_buffer(0, v.slice(..));
                pass.set_index_buffer(i.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(g.features.clone(), 0, 0..1);
            }
        }
    }
}

impl egui_wgpu::CallbackTrait for ViewportCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(gpu) = resources.get_mut::<ViewportGpu>() else {
            return Vec::new();
        };
        if self.size_px[0] == 0 || self.size_px[1] == 0 {
            return Vec::new();
        }
        if gpu.geometry.as_ref().map(|g| g.generation) != Some(self.scene.generation) {
            gpu.upload_geometry(device, &self.scene);
        }
        gpu.upload_style(device, queue, self);
        let mut u = self.uniforms;
        u.flags[1] = if gpu.target_format.is_srgb() {
            1.0
        } else {
            0.0
        };
        queue.write_buffer(&gpu.uniforms, 0, bytemuck::bytes_of(&u));
        gpu.ensure_offscreen(device, self.size_px);
        gpu.draw(encoder, self);
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        let Some(gpu) = resources.get::<ViewportGpu>() else {
            return;
        };
        let Some(off) = &gpu.offscreen else { return };
        render_pass.set_pipeline(&gpu.blit);
        render_pass.set_bind_group(0, &off.blit, &[]);
        render_pass.draw(0..3, 0..1);
    }
}
