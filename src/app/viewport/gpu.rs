//! The viewport's own wgpu pipeline: it renders the scene into an offscreen colour + depth target
//! (so depth testing and MSAA do not depend on egui's pass) that egui then draws as a texture.
//!
//! Pipelines and buffers are created once and live in egui-wgpu's `callback_resources`; each frame a
//! [`ViewportCallback`] uploads the scene when it changed, writes the camera uniform and records the
//! render pass in `prepare`. The robot's meshes ([`PackedMeshes`]) are uploaded once per robot.
//!
//! **WebGL2-safe** (a browser build draws through wgpu's WebGL2 backend): no storage buffers (instances
//! are vertex attributes), no base vertex (offsets are baked into the indices), no first instance (a
//! group's instances are a slice of the instance buffer bound at its offset), 32-bit indices.

use super::mesh_pack::PackedMeshes;
use super::primitives::{MeshVertex, unit_box, unit_cylinder, unit_sphere};
use super::scene::{ColorVertex, Geometry, MeshInstance, Primitive, SceneData};
use eframe::egui_wgpu::{self, wgpu};
use std::ops::Range;
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
struct GpuInstance {
    model: [[f32; 4]; 4],
    normal: [[f32; 4]; 3],
    color: [f32; 4],
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
            // Freed now: on the web, wgpu leaves a dropped buffer to JavaScript's garbage collector.
            self.buffer.destroy();
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
    pipelines: Pipelines,
    uniform_buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    meshes: UnitMeshes,
    /// The robot's meshes (the pack of the last scene that had one).
    robot_meshes: Option<RobotMeshesGpu>,
    instances: DynBuffer,
    /// What to draw: each geometry with its instances (a range of the instance buffer).
    draws: Vec<(Geometry, Range<u32>)>,
    lines: DynBuffer,
    triangles: DynBuffer,
    scene_version: Option<u64>,
    targets: Option<Targets>,
    /// What the targets currently hold (scene version, camera), to skip re-rendering an unchanged view.
    rendered: Option<(u64, FrameUniform)>,
}

fn primitive_index(p: Primitive) -> usize {
    match p {
        Primitive::Box => 0,
        Primitive::Cylinder => 1,
        Primitive::Sphere => 2,
    }
}

/// A robot's packed meshes on the GPU.
struct RobotMeshesGpu {
    pack_id: u64,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    ranges: Vec<Range<u32>>,
}

impl RobotMeshesGpu {
    fn new(device: &wgpu::Device, pack: &PackedMeshes) -> Self {
        // An empty buffer cannot be created with contents: keep one vertex / one index.
        let vertices: &[MeshVertex] = if pack.vertices.is_empty() {
            &[MeshVertex {
                position: [0.0; 3],
                normal: [0.0, 0.0, 1.0],
            }]
        } else {
            &pack.vertices
        };
        let indices: &[u32] = if pack.indices.is_empty() {
            &[0]
        } else {
            &pack.indices
        };
        Self {
            pack_id: pack.id,
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("viewport robot mesh vertices"),
                contents: bytemuck::cast_slice(vertices),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("viewport robot mesh indices"),
                contents: bytemuck::cast_slice(indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
            ranges: pack.ranges.clone(),
        }
    }
}

/// The render pipelines: instanced unit meshes, coloured lines and triangles, the background.
struct Pipelines {
    mesh: wgpu::RenderPipeline,
    line: wgpu::RenderPipeline,
    triangle: wgpu::RenderPipeline,
    background: wgpu::RenderPipeline,
}

/// What differs between the pipelines (all draw into [`COLOR_FORMAT`] + [`DEPTH_FORMAT`] with the
/// shader's `vs_main` and `fs_main`).
struct PipelineSpec<'a> {
    label: &'a str,
    layout: &'a wgpu::PipelineLayout,
    shader: &'a wgpu::ShaderModule,
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    topology: wgpu::PrimitiveTopology,
    depth_write: bool,
    depth_compare: wgpu::CompareFunction,
    blend: Option<wgpu::BlendState>,
}

fn create_pipeline(
    device: &wgpu::Device,
    spec: PipelineSpec<'_>,
    sample_count: u32,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: spec.shader,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: spec.buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: spec.topology,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(spec.depth_write),
            depth_compare: Some(spec.depth_compare),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: sample_count,
            mask: !0,
            alpha_to_coverage_enabled: false,
        },
        fragment: Some(wgpu::FragmentState {
            module: spec.shader,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: COLOR_FORMAT,
                blend: spec.blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn shader(device: &wgpu::Device, label: &str, wgsl: &'static str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    })
}

impl Pipelines {
    fn new(device: &wgpu::Device, frame_layout: &wgpu::BindGroupLayout, sample_count: u32) -> Self {
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport layout"),
            bind_group_layouts: &[Some(frame_layout)],
            immediate_size: 0,
        });
        let empty_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport background layout"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
        let mesh_shader = shader(
            device,
            "mesh.wgsl",
            include_str!("../../../shaders/mesh.wgsl"),
        );
        let line_shader = shader(
            device,
            "lines.wgsl",
            include_str!("../../../shaders/lines.wgsl"),
        );
        let background_shader = shader(
            device,
            "background.wgsl",
            include_str!("../../../shaders/background.wgsl"),
        );
        let mesh_buffers = [
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<MeshVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            }),
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<GpuInstance>() as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &wgpu::vertex_attr_array![
                    2 => Float32x4, 3 => Float32x4, 4 => Float32x4, 5 => Float32x4,
                    6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 9 => Float32x4
                ],
            }),
        ];
        let color_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<ColorVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
        })];
        let colored = |label, topology, depth_write| PipelineSpec {
            label,
            layout: &layout,
            shader: &line_shader,
            buffers: &color_buffers,
            topology,
            depth_write,
            depth_compare: wgpu::CompareFunction::LessEqual,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
        };
        let pipeline = |spec| create_pipeline(device, spec, sample_count);
        Self {
            mesh: pipeline(PipelineSpec {
                label: "viewport mesh pipeline",
                layout: &layout,
                shader: &mesh_shader,
                buffers: &mesh_buffers,
                topology: wgpu::PrimitiveTopology::TriangleList,
                depth_write: true,
                depth_compare: wgpu::CompareFunction::LessEqual,
                blend: None,
            }),
            line: pipeline(colored(
                "viewport line pipeline",
                wgpu::PrimitiveTopology::LineList,
                true,
            )),
            triangle: pipeline(colored(
                "viewport triangle pipeline",
                wgpu::PrimitiveTopology::TriangleList,
                false,
            )),
            background: pipeline(PipelineSpec {
                label: "viewport background pipeline",
                layout: &empty_layout,
                shader: &background_shader,
                buffers: &[],
                topology: wgpu::PrimitiveTopology::TriangleList,
                depth_write: false,
                depth_compare: wgpu::CompareFunction::Always,
                blend: None,
            }),
        }
    }
}

/// The three unit primitives in one vertex and one index buffer (vertex offsets baked in).
struct UnitMeshes {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// Index ranges of box, cylinder, sphere.
    ranges: [Range<u32>; 3],
}

impl UnitMeshes {
    fn new(device: &wgpu::Device) -> Self {
        let meshes = [unit_box(), unit_cylinder(32), unit_sphere(24, 16)];
        let mut vertices: Vec<MeshVertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let ranges = meshes.map(|(v, i)| {
            let start = indices.len() as u32;
            let offset = vertices.len() as u32;
            vertices.extend(v);
            indices.extend(i.iter().map(|k| k + offset));
            start..indices.len() as u32
        });
        Self {
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("viewport unit mesh vertices"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("viewport unit mesh indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
            ranges,
        }
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
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
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
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform_buffer.as_entire_binding(),
            }],
        });
        Self {
            sample_count,
            pipelines: Pipelines::new(device, &frame_layout, sample_count),
            uniform_buffer,
            bind_group,
            meshes: UnitMeshes::new(device),
            robot_meshes: None,
            instances: DynBuffer::new(device, "viewport instances", wgpu::BufferUsages::VERTEX),
            draws: Vec::new(),
            lines: DynBuffer::new(device, "viewport lines", wgpu::BufferUsages::VERTEX),
            triangles: DynBuffer::new(device, "viewport triangles", wgpu::BufferUsages::VERTEX),
            scene_version: None,
            targets: None,
            rendered: None,
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
        self.rendered = None;
        self.targets = Some(Targets {
            size_px,
            msaa_view,
            resolve_view: resolve_view.clone(),
            depth_view,
        });
        Some(resolve_view)
    }

    fn upload_scene(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, scene: &SceneData) {
        if let Some(pack) = &scene.meshes
            && self.robot_meshes.as_ref().map(|m| m.pack_id) != Some(pack.id)
        {
            // The previous pack's buffers freed now: on the web, wgpu leaves a dropped buffer to
            // JavaScript's garbage collector (a new robot or mesh detail uploads megabytes).
            if let Some(old) = self.robot_meshes.take() {
                old.vertices.destroy();
                old.indices.destroy();
            }
            self.robot_meshes = Some(RobotMeshesGpu::new(device, pack));
        }
        let mut sorted: Vec<&MeshInstance> = scene.instances.iter().collect();
        crate::sort::sort_by_key(&mut sorted, |i| i.geometry);
        self.draws.clear();
        for (k, instance) in sorted.iter().enumerate() {
            let k = k as u32;
            match self.draws.last_mut() {
                Some((geometry, range)) if *geometry == instance.geometry => range.end = k + 1,
                _ => self.draws.push((instance.geometry, k..k + 1)),
            }
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
        pass.set_pipeline(&self.pipelines.background);
        pass.draw(0..3, 0..1);

        pass.set_bind_group(0, &self.bind_group, &[]);
        if self.instances.len > 0 {
            pass.set_pipeline(&self.pipelines.mesh);
            let stride = std::mem::size_of::<GpuInstance>() as u64;
            // Which buffers are bound: the unit primitives' (false) or the robot meshes' (true).
            let mut bound: Option<bool> = None;
            for (geometry, instances) in &self.draws {
                let (robot, indices) = match *geometry {
                    Geometry::Primitive(p) => {
                        (false, self.meshes.ranges[primitive_index(p)].clone())
                    }
                    Geometry::Mesh(k) => {
                        match self
                            .robot_meshes
                            .as_ref()
                            .and_then(|m| m.ranges.get(k as usize))
                        {
                            Some(range) => (true, range.clone()),
                            None => continue,
                        }
                    }
                };
                if bound != Some(robot) {
                    let (vertices, index_buffer) = match (&self.robot_meshes, robot) {
                        (Some(m), true) => (&m.vertices, &m.indices),
                        _ => (&self.meshes.vertices, &self.meshes.indices),
                    };
                    pass.set_vertex_buffer(0, vertices.slice(..));
                    pass.set_index_buffer(index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                    bound = Some(robot);
                }
                // The group's instances bound at their offset: no first instance needed.
                pass.set_vertex_buffer(
                    1,
                    self.instances
                        .buffer
                        .slice(instances.start as u64 * stride..instances.end as u64 * stride),
                );
                pass.draw_indexed(indices, 0, 0..instances.len() as u32);
            }
        }
        if self.lines.len > 0 {
            pass.set_pipeline(&self.pipelines.line);
            pass.set_vertex_buffer(0, self.lines.buffer.slice(..));
            pass.draw(0..self.lines.len, 0..1);
        }
        if self.triangles.len > 0 {
            pass.set_pipeline(&self.pipelines.triangle);
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
        // The offscreen image persists: render only when the scene or the camera changed.
        let key = (self.scene.version, self.uniform);
        if gpu.rendered == Some(key) {
            return Vec::new();
        }
        if gpu.scene_version != Some(self.scene.version) {
            gpu.upload_scene(device, queue, &self.scene);
        }
        queue.write_buffer(&gpu.uniform_buffer, 0, bytemuck::bytes_of(&self.uniform));
        gpu.render(egui_encoder);
        gpu.rendered = Some(key);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_uniform_matches_the_wgsl_layout() {
        // mat4x4 + 2 × vec4 = 96 bytes.
        assert_eq!(std::mem::size_of::<FrameUniform>(), 96);
        assert_eq!(std::mem::size_of::<GpuInstance>(), 8 * 16);
    }
}
