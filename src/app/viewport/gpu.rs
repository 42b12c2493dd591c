//! The viewport's own wgpu pipeline: it renders the scene into an offscreen colour + depth target
//! (so depth testing and MSAA do not depend on egui's pass) that egui then draws as a texture.
//!
//! Pipelines and buffers are created once and live in egui-wgpu's `callback_resources`; each frame a
//! [`ViewportCallback`] uploads the scene when it changed, writes the camera uniform and records the
//! render pass in `prepare`.

use super::scene::{ColorVertex, MeshInstance, Primitive, SceneData};
use eframe::egui_wgpu::{self, wgpu};
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// Colour format of the offscreen target; egui samples it as an ordinary sRGB texture.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Per-frame uniform shared by all shaders (`struct Frame` in the WGSL files).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniform {
    pub view_proj: [f32; 16],
    /// Direction towards the light, w = ambient factor.
    pub light_dir: [f32; 4],
    /// Camera position, w unused.
    pub eye: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct MeshVertex {
    position: [f32; 3],
    normal: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuInstance {
    model: [[f32; 4]; 4],
    normal: [[f32; 4]; 3],
    color: [f32; 4],
}

/// A unit primitive's index range in the shared mesh buffers.
#[derive(Clone, Copy, Debug)]
struct MeshRange {
    first_index: u32,
    index_count: u32,
    base_vertex: i32,
}

/// A growable vertex/instance buffer.
struct DynBuffer {
    buffer: wgpu::Buffer,
    capacity_bytes: u64,
    len: u32,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl DynBuffer {
    fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Self {
        let capacity_bytes = 64 * 1024;
        Self {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: capacity_bytes,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            capacity_bytes,
            len: 0,
            usage,
            label,
        }
    }

    fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, bytes: &[u8], len: u32) {
        let needed = bytes.len() as u64;
        if needed > self.capacity_bytes {
            self.capacity_bytes = needed.next_power_of_two();
            self.buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size: self.capacity_bytes,
                usage: self.usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
        if !bytes.is_empty() {
            queue.write_buffer(&self.buffer, 0, bytes);
        }
        self.len = len;
    }
}

/// The offscreen targets of one size.
struct Targets {
    size_px: [u32; 2],
    /// Multisampled colour (when MSAA is on).
    msaa_view: Option<wgpu::TextureView>,
    /// Single-sampled colour that egui samples.
    resolve_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
}

/// Everything the viewport keeps on the GPU; stored in egui-wgpu's callback resources.
pub struct ViewportGpu {
    sample_count: u32,
    mesh_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    triangle_pipeline: wgpu::RenderPipeline,
    background_pipeline: wgpu::RenderPipeline,
    uniform_buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    mesh_vertices: wgpu::Buffer,
    mesh_indices: wgpu::Buffer,
    mesh_ranges: [MeshRange; 3],
    instances: DynBuffer,
    /// Instance ranges per primitive (box, cylinder, sphere).
    instance_ranges: [std::ops::Range<u32>; 3],
    lines: DynBuffer,
    triangles: DynBuffer,
    scene_version: Option<u64>,
    targets: Option<Targets>,
}

fn primitive_index(p: Primitive) -> usize {
    match p {
        Primitive::Box => 0,
        Primitive::Cylinder => 1,
        Primitive::Sphere => 2,
    }
}

impl ViewportGpu {
    /// Create the pipelines and buffers. `sample_count` is 1 (no MSAA) or 4.
    pub fn new(device: &wgpu::Device, sample_count: u32) -> Self {
        let uniform_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewport frame uniform"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport frame layout"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewport frame bind group"),
            layout: &bind_group_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform_buffer.as_entire_binding(),
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport layout"),
            bind_group_layouts: &[Some(&bind_group_layout)],
            immediate_size: 0,
        });
        let empty_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport background layout"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });

        let mesh_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../shaders/mesh.wgsl").into()),
        });
        let line_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lines.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../shaders/lines.wgsl").into()),
        });
        let background_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("background.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                include_str!("../../../shaders/background.wgsl").into(),
            ),
        });

        let multisample = wgpu::MultisampleState {
            count: sample_count,
            mask: !0,
            alpha_to_coverage_enabled: false,
        };
        let depth = |write: bool| wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(write),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        };
        let opaque_target = [Some(wgpu::ColorTargetState {
            format: COLOR_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let blended_target = [Some(wgpu::ColorTargetState {
            format: COLOR_FORMAT,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        })];

        let mesh_vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
        };
        let instance_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<GpuInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &wgpu::vertex_attr_array![
                2 => Float32x4, 3 => Float32x4, 4 => Float32x4, 5 => Float32x4,
                6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 9 => Float32x4
            ],
        };
        let color_vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<ColorVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
        };

        let mesh_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("viewport mesh pipeline"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &mesh_shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(mesh_vertex_layout), Some(instance_layout)],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(depth(true)),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &mesh_shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &opaque_target,
            }),
            multiview_mask: None,
            cache: None,
        });
        let color_pipeline = |label: &str, topology, write_depth: bool, targets| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &line_shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(color_vertex_layout.clone())],
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(depth(write_depth)),
                multisample,
                fragment: Some(wgpu::FragmentState {
                    module: &line_shader,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let line_pipeline = color_pipeline(
            "viewport line pipeline",
            wgpu::PrimitiveTopology::LineList,
            true,
            &blended_target,
        );
        let triangle_pipeline = color_pipeline(
            "viewport triangle pipeline",
            wgpu::PrimitiveTopology::TriangleList,
            false,
            &blended_target,
        );
        let background_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("viewport background pipeline"),
            layout: Some(&empty_layout),
            vertex: wgpu::VertexState {
                module: &background_shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &background_shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &opaque_target,
            }),
            multiview_mask: None,
            cache: None,
        });

        // The three unit primitives in one vertex and one index buffer.
        let meshes = [unit_box(), unit_cylinder(32), unit_sphere(24, 16)];
        let mut vertices: Vec<MeshVertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut mesh_ranges = [MeshRange {
            first_index: 0,
            index_count: 0,
            base_vertex: 0,
        }; 3];
        for (k, (v, i)) in meshes.into_iter().enumerate() {
            mesh_ranges[k] = MeshRange {
                first_index: indices.len() as u32,
                index_count: i.len() as u32,
                base_vertex: vertices.len() as i32,
            };
            vertices.extend(v);
            indices.extend(i);
        }
        let mesh_vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("viewport unit mesh vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let mesh_indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("viewport unit mesh indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });

        Self {
            sample_count,
            mesh_pipeline,
            line_pipeline,
            triangle_pipeline,
            background_pipeline,
            uniform_buffer,
            bind_group,
            mesh_vertices,
            mesh_indices,
            mesh_ranges,
            instances: DynBuffer::new(device, "viewport instances", wgpu::BufferUsages::VERTEX),
            instance_ranges: [0..0, 0..0, 0..0],
            lines: DynBuffer::new(device, "viewport lines", wgpu::BufferUsages::VERTEX),
            triangles: DynBuffer::new(device, "viewport triangles", wgpu::BufferUsages::VERTEX),
            scene_version: None,
            targets: None,
        }
    }

    /// Make sure the offscreen targets have `size_px`. Returns the view egui should sample when it
    /// was (re)created, so the caller can (re)register it as an egui texture.
    pub fn ensure_targets(
        &mut self,
        device: &wgpu::Device,
        size_px: [u32; 2],
    ) -> Option<wgpu::TextureView> {
        let size_px = [size_px[0].clamp(1, 8192), size_px[1].clamp(1, 8192)];
        if self.targets.as_ref().is_some_and(|t| t.size_px == size_px) {
            return None;
        }
        let extent = wgpu::Extent3d {
            width: size_px[0],
            height: size_px[1],
            depth_or_array_layers: 1,
        };
        let texture = |label: &str, format, samples, usage| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: extent,
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        let resolve_view = texture(
            "viewport colour",
            COLOR_FORMAT,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let msaa_view = (self.sample_count > 1).then(|| {
            texture(
                "viewport colour (MSAA)",
                COLOR_FORMAT,
                self.sample_count,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            )
        });
        let depth_view = texture(
            "viewport depth",
            DEPTH_FORMAT,
            self.sample_count,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        self.targets = Some(Targets {
            size_px,
            msaa_view,
            resolve_view: resolve_view.clone(),
            depth_view,
        });
        Some(resolve_view)
    }

    fn upload_scene(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, scene: &SceneData) {
        let mut sorted: Vec<&MeshInstance> = scene.instances.iter().collect();
        sorted.sort_by_key(|i| primitive_index(i.primitive));
        let mut ranges = [0..0, 0..0, 0..0];
        for (k, range) in ranges.iter_mut().enumerate() {
            let start = sorted.partition_point(|i| primitive_index(i.primitive) < k) as u32;
            let end = sorted.partition_point(|i| primitive_index(i.primitive) <= k) as u32;
            *range = start..end;
        }
        let gpu: Vec<GpuInstance> = sorted
            .iter()
            .map(|i| GpuInstance {
                model: i.model,
                normal: i.normal,
                color: i.color,
            })
            .collect();
        self.instances
            .upload(device, queue, bytemuck::cast_slice(&gpu), gpu.len() as u32);
        self.instance_ranges = ranges;
        self.lines.upload(
            device,
            queue,
            bytemuck::cast_slice(&scene.lines),
            scene.lines.len() as u32,
        );
        self.triangles.upload(
            device,
            queue,
            bytemuck::cast_slice(&scene.triangles),
            scene.triangles.len() as u32,
        );
        self.scene_version = Some(scene.version);
    }

    fn render(&self, encoder: &mut wgpu::CommandEncoder) {
        let Some(targets) = &self.targets else {
            return;
        };
        let (view, resolve_target) = match &targets.msaa_view {
            Some(msaa) => (msaa, Some(&targets.resolve_view)),
            None => (&targets.resolve_view, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("viewport pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth_view,
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
        pass.set_pipeline(&self.background_pipeline);
        pass.draw(0..3, 0..1);

        pass.set_bind_group(0, &self.bind_group, &[]);
        if self.instances.len > 0 {
            pass.set_pipeline(&self.mesh_pipeline);
            pass.set_vertex_buffer(0, self.mesh_vertices.slice(..));
            pass.set_vertex_buffer(1, self.instances.buffer.slice(..));
            pass.set_index_buffer(self.mesh_indices.slice(..), wgpu::IndexFormat::Uint32);
            for (range, mesh) in self.instance_ranges.iter().zip(&self.mesh_ranges) {
                if !range.is_empty() {
                    pass.draw_indexed(
                        mesh.first_index..mesh.first_index + mesh.index_count,
                        mesh.base_vertex,
                        range.clone(),
                    );
                }
            }
        }
        if self.lines.len > 0 {
            pass.set_pipeline(&self.line_pipeline);
            pass.set_vertex_buffer(0, self.lines.buffer.slice(..));
            pass.draw(0..self.lines.len, 0..1);
        }
        if self.triangles.len > 0 {
            pass.set_pipeline(&self.triangle_pipeline);
            pass.set_vertex_buffer(0, self.triangles.buffer.slice(..));
            pass.draw(0..self.triangles.len, 0..1);
        }
    }
}

/// One frame's draw request: the scene (re-uploaded only when its version changes) and the camera.
pub struct ViewportCallback {
    pub scene: Arc<SceneData>,
    pub uniform: FrameUniform,
}

impl egui_wgpu::CallbackTrait for ViewportCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen_descriptor: &egui_wgpu::ScreenDescriptor,
        egui_encoder: &mut wgpu::CommandEncoder,
        callback_resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        let Some(gpu) = callback_resources.get_mut::<ViewportGpu>() else {
            return Vec::new();
        };
        if gpu.scene_version != Some(self.scene.version) {
            gpu.upload_scene(device, queue, &self.scene);
        }
        queue.write_buffer(&gpu.uniform_buffer, 0, bytemuck::bytes_of(&self.uniform));
        gpu.render(egui_encoder);
        Vec::new()
    }

    fn paint(
        &self,
        _info: eframe::egui::PaintCallbackInfo,
        _render_pass: &mut wgpu::RenderPass<'static>,
        _callback_resources: &egui_wgpu::CallbackResources,
    ) {
        // The scene was rendered offscreen in `prepare`; egui draws the target as an image.
    }
}

// ---- unit primitives -------------------------------------------------------------------------------

/// Cube [-1, 1]³ with flat normals.
fn unit_box() -> (Vec<MeshVertex>, Vec<u32>) {
    let mut v = Vec::with_capacity(24);
    let mut i = Vec::with_capacity(36);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = v.len() as u32;
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0; 3];
                p[axis] = sign;
                p[u_axis] = su;
                p[v_axis] = sv;
                v.push(MeshVertex {
                    position: p,
                    normal: n,
                });
            }
            i.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    (v, i)
}

/// Cylinder of radius 1 from z = -1 to z = 1, with caps.
fn unit_cylinder(segments: u32) -> (Vec<MeshVertex>, Vec<u32>) {
    let mut v = Vec::new();
    let mut i = Vec::new();
    for k in 0..=segments {
        let a = k as f32 / segments as f32 * std::f32::consts::TAU;
        let (s, c) = a.sin_cos();
        v.push(MeshVertex {
            position: [c, s, -1.0],
            normal: [c, s, 0.0],
        });
        v.push(MeshVertex {
            position: [c, s, 1.0],
            normal: [c, s, 0.0],
        });
    }
    for k in 0..segments {
        let b = 2 * k;
        i.extend([b, b + 2, b + 1, b + 1, b + 2, b + 3]);
    }
    for z in [-1.0f32, 1.0] {
        let centre = v.len() as u32;
        v.push(MeshVertex {
            position: [0.0, 0.0, z],
            normal: [0.0, 0.0, z],
        });
        for k in 0..=segments {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            let (s, c) = a.sin_cos();
            v.push(MeshVertex {
                position: [c, s, z],
                normal: [0.0, 0.0, z],
            });
        }
        for k in 0..segments {
            i.extend([centre, centre + 1 + k, centre + 2 + k]);
        }
    }
    (v, i)
}

/// Sphere of radius 1 (latitude/longitude grid).
fn unit_sphere(segments: u32, rings: u32) -> (Vec<MeshVertex>, Vec<u32>) {
    let mut v = Vec::new();
    let mut i = Vec::new();
    for r in 0..=rings {
        let phi = r as f32 / rings as f32 * std::f32::consts::PI;
        let (sp, cp) = phi.sin_cos();
        for k in 0..=segments {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            let (s, c) = a.sin_cos();
            let p = [sp * c, sp * s, cp];
            v.push(MeshVertex {
                position: p,
                normal: p,
            });
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for k in 0..segments {
            let a = r * row + k;
            let b = a + row;
            i.extend([a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    (v, i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_meshes_index_their_own_vertices_and_have_unit_normals() {
        for (v, i) in [unit_box(), unit_cylinder(16), unit_sphere(12, 8)] {
            assert_eq!(i.len() % 3, 0);
            assert!(i.iter().all(|&k| (k as usize) < v.len()));
            for vert in &v {
                let n = vert.normal;
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                assert!((len - 1.0).abs() < 1e-5, "{n:?}");
                assert!(vert.position.iter().all(|c| c.abs() <= 1.0 + 1e-6));
            }
        }
    }

    #[test]
    fn frame_uniform_matches_the_wgsl_layout() {
        // mat4x4 + 2 × vec4 = 96 bytes.
        assert_eq!(std::mem::size_of::<FrameUniform>(), 96);
        assert_eq!(std::mem::size_of::<GpuInstance>(), 8 * 16);
    }
}
