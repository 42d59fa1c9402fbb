//! Embedding ssbvb in an existing wgpu renderer, headless: this program creates its own
//! device, draws its own triangle geometry (a ground quad) into its own colour and
//! depth-stencil targets, then lets `ssbvb_passes::runtime::embed::VoxelLayer` draw the Stanford
//! bunny into the same targets, depth-tested against the quad, and writes `embed.png`.
//!
//! `cargo run --release -p ssbvb-passes --example embed [-- OUT.png]`

use std::sync::Arc;

use glam::{DAffine3, DVec3, Mat4};
use ssbvb_gpu::scene::{LodPolicy, Scene, VoxelObject};
use ssbvb_gpu::wgpu;
use ssbvb_gpu::wgpu::util::DeviceExt;
use ssbvb_passes::Profiling;
use ssbvb_passes::runtime::embed::VoxelLayer;
use ssbvb_voxel::camera::Camera;

const SIZE: (u32, u32) = (480, 360);

/// The host application's own forward shader: flat-shaded geometry, reversed-Z depth.
const HOST_SHADER: &str = r#"
@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
struct Out { @builtin(position) pos: vec4<f32>, @location(0) color: vec3<f32> }
@vertex fn vs(@location(0) p: vec3<f32>, @location(1) c: vec3<f32>) -> Out {
    return Out(view_proj * vec4(p, 1.0), c);
}
@fragment fn fs(i: Out) -> @location(0) vec4<f32> { return vec4(i.color, 1.0); }
"#;

/// The host's device: any adapter, its full limits, `Depth32FloatStencil8` when it has it.
struct Host {
    instance: wgpu::Instance,
    adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    depth_format: wgpu::TextureFormat,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "embed.png".into());
    let host = host_device()?;
    let (color, depth) = host_targets(&host);
    let camera = Camera {
        position: DVec3::new(1.9, 0.9, 2.7),
        look_at: DVec3::new(0.0, -0.15, 0.0),
        fov_y_deg: 40.0,
        ..Camera::default()
    };
    draw_ground(&host, &camera, &color, &depth);
    draw_voxels(&host, &camera, &color, &depth)?;
    let ctx = ssbvb_gpu::GpuContext::from_parts(
        host.instance.clone(),
        host.adapter.clone(),
        host.device.clone(),
        host.queue.clone(),
    );
    let img = ctx.read_texture(&color, wgpu::TextureAspect::All)?;
    ssbvb_gpu::readback::write_png_rgba8(out.as_ref(), SIZE.0, SIZE.1, &img.bytes)?;
    println!("wrote {out}");
    Ok(())
}

/// Creates the host's device (ssbvb uses whatever device it is given).
fn host_device() -> Result<Host, Box<dyn std::error::Error>> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let features = adapter.features() & wgpu::Features::DEPTH32FLOAT_STENCIL8;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("host"),
        required_features: features,
        required_limits: adapter.limits(),
        ..Default::default()
    }))?;
    println!("adapter: {}", adapter.get_info().name);
    let depth_format = if features.contains(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
        wgpu::TextureFormat::Depth32FloatStencil8
    } else {
        wgpu::TextureFormat::Depth24PlusStencil8
    };
    Ok(Host {
        instance,
        adapter,
        device,
        queue,
        depth_format,
    })
}

/// The host's colour and depth-stencil targets.
fn host_targets(host: &Host) -> (wgpu::Texture, wgpu::Texture) {
    let (device, depth_format) = (&host.device, host.depth_format);
    let target = |format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: SIZE.0,
                height: SIZE.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let color = target(
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = target(
        depth_format,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    );

    (color, depth)
}

/// The host's own forward pass: a ground quad into its colour and depth-stencil targets.
fn draw_ground(host: &Host, camera: &Camera, color: &wgpu::Texture, depth: &wgpu::Texture) {
    let (device, queue, depth_format) = (&host.device, &host.queue, host.depth_format);
    // The host draws its ground quad with the same camera conventions (camera-relative
    // positions, reversed Z).
    let view_proj: Mat4 = (camera.projection(SIZE.0 as f64 / SIZE.1 as f64)
        * camera.view_rotation_matrix())
    .as_mat4();
    let eye = camera.position.as_vec3();
    let quad: Vec<f32> = [
        [-3.0f32, -0.95, -3.0],
        [3.0, -0.95, -3.0],
        [3.0, -0.95, 3.0],
        [-3.0, -0.95, 3.0],
    ]
    .iter()
    .zip([
        [0.5f32, 0.3, 0.2],
        [0.2, 0.5, 0.3],
        [0.2, 0.3, 0.5],
        [0.5, 0.5, 0.2],
    ])
    .flat_map(|(p, c)| [p[0] - eye.x, p[1] - eye.y, p[2] - eye.z, c[0], c[1], c[2]])
    .collect();
    let vb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&quad),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let ib = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&[0u32, 2, 1, 0, 3, 2]),
        usage: wgpu::BufferUsages::INDEX,
    });
    let ub = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&view_proj.to_cols_array()),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("host"),
        source: wgpu::ShaderSource::Wgsl(HOST_SHADER.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("host"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 24,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            })],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::TextureFormat::Rgba8UnormSrgb.into())],
        }),
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: depth_format,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    });
    let bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: ub.as_entire_binding(),
        }],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let cv = color.create_view(&Default::default());
        let dv = depth.create_view(&Default::default());
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host triangles"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &cv,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 0.05,
                        g: 0.07,
                        b: 0.12,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Store,
                }),
            }),
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.set_vertex_buffer(0, vb.slice(..));
        pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..6, 0, 0..1);
    }
    queue.submit([enc.finish()]);
}

/// ssbvb's layer: the bunny drawn into the host's targets, depth-tested against its quad.
fn draw_voxels(
    host: &Host,
    camera: &Camera,
    color: &wgpu::Texture,
    depth: &wgpu::Texture,
) -> Result<(), Box<dyn std::error::Error>> {
    // ssbvb draws the voxel objects into the same targets.
    let bunny = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/models/bunny.obj");
    let (asset, outcome) = ssbvb_voxel::cache::load_or_prepare(
        bunny.as_ref(),
        8,
        None,
        &ssbvb_voxel::progress::NoProgress,
    )?;
    println!("asset: {outcome}");
    let scene = Scene {
        objects: vec![VoxelObject {
            asset: Arc::new(asset),
            instances: vec![DAffine3::IDENTITY],
            lod: LodPolicy::Fixed(8),
        }],
        ..Default::default()
    };
    let mut layer = VoxelLayer::new(
        &host.instance,
        &host.adapter,
        &host.device,
        &host.queue,
        scene,
        None,
        color,
        depth,
    )?;
    let stats = layer.render(camera, Profiling::Timestamps)?;
    println!(
        "voxel layer: {:.2} ms wall, {} visible instance(s)",
        stats.frame_wall_ms, stats.visible_instances
    );
    Ok(())
}
