//! The scene on the GPU: every LOD of every asset in shared buffers, proxy meshes,
//! triangle meshes, and the per-frame constants and visible instances (group 0 of every
//! pass; WGSL declarations in `shaders/common.inc.wgsl`).

use glam::{DAffine3, DMat4, DVec3};
use ssbvb_gpu::wgpu::util::DeviceExt;
use ssbvb_gpu::{GpuContext, wgpu};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::lookup::NODE_WORDS;

use crate::PassError;
use crate::scene::Scene;
use crate::streaming::{
    PINNED_LEVEL, PagedLayoutBuilder, StreamBuffers, Streaming, StreamingOptions, StreamingStats,
};
pub use crate::visibility::choose_level;

mod dynamic;
mod layout;
mod pools;

pub use dynamic::{DynamicLevel, DynamicObject, DynamicRoom};
pub(crate) use dynamic::{copy_words, copy_words_from_chunks};

use crate::visibility::{frame_uniform, instance_bvh, mat, visible_instances};
pub use layout::*;
pub use pools::{COLOR_CHUNKS, NODE_CHUNKS, NORMAL_CHUNKS, SCENE_STORAGE_BUFFERS, StreamChunks};
use pools::{checked_u32, storage};
use pools::{chunked, plan_pools};

/// The scene on the GPU.
pub struct GpuScene {
    /// The CPU scene (transforms are read each frame).
    pub scene: Scene,
    /// How the streams are split over bindings (passes that upload their own large
    /// buffers split them alike).
    pub chunks: StreamChunks,
    /// Group 0 layout shared by every pass.
    pub layout: wgpu::BindGroupLayout,
    /// Group 0 of the current frame.
    pub bind_group: wgpu::BindGroup,
    /// Per-frame constants.
    pub frame_buffer: wgpu::Buffer,
    /// Visible instances (room for every instance of the scene).
    pub instance_buffer: wgpu::Buffer,
    /// The hierarchy over the visible instances' boxes (room for every instance).
    pub bvh_buffer: wgpu::Buffer,
    /// LOD table.
    pub lod_buffer: wgpu::Buffer,
    /// Voxel colours (linear RGBA8, one word per voxel), in [`COLOR_CHUNKS`] bindings.
    pub color_buffers: Vec<wgpu::Buffer>,
    /// Voxel normals (16-bit octahedral, two per word), in [`NORMAL_CHUNKS`] bindings.
    pub normal_buffers: Vec<wgpu::Buffer>,
    /// The lookup trees' nodes (12 bytes each), in [`NODE_CHUNKS`] bindings.
    pub lookup_buffers: Vec<wgpu::Buffer>,
    /// Proxy vertices (object space, vec4).
    pub proxy_vertices: wgpu::Buffer,
    /// Proxy indices.
    pub proxy_indices: wgpu::Buffer,
    /// `lod_base[object]`: index of the object's level 0 in the LOD table.
    pub lod_base: Vec<u32>,
    /// Per LOD-table entry, the object-space box of its voxels (`None`: no voxels): the
    /// instance hierarchy bounds these rather than the whole `[-1, 1]³`.
    pub lod_bounds: Vec<Option<(DVec3, DVec3)>>,
    /// `proxies[object][level]`.
    pub proxies: Vec<Vec<ProxyRange>>,
    /// Triangle meshes, one per scene triangle object.
    pub meshes: Vec<GpuTriangleMesh>,
    /// Instances drawn this frame, in instance-buffer order.
    pub visible: Vec<VisibleInstance>,
    /// GPU memory per object (the whole asset, as uploaded without a budget).
    pub memory: Vec<ObjectMemory>,
    /// The page cache under a budget (`None`: every level resident).
    pub streaming: Option<crate::streaming::Streaming>,
    /// Objects whose voxels change on the GPU, with their room in the streams.
    pub dynamic: Vec<DynamicObject>,
    /// Page feedback binding (a small unused buffer without a budget).
    _feedback_dummy: Option<wgpu::Buffer>,
    /// Voxel indices of the colour stream (for unique-voxel keys under a budget).
    voxel_slots: u64,
    /// The camera of the current frame.
    pub camera: Camera,
    /// Screen size of the current frame.
    pub screen: (u32, u32),
}

/// The object-space box of a level's voxels (their cells' union), `None` when it has none.
fn voxel_bounds(lod: &ssbvb_voxel::asset::LodLevel) -> Option<(DVec3, DVec3)> {
    let mut lo = [u32::MAX; 3];
    let mut hi = [0u32; 3];
    for v in &lod.point_cloud.voxels {
        let c = v.cell();
        for a in 0..3 {
            lo[a] = lo[a].min(c[a]);
            hi[a] = hi[a].max(c[a]);
        }
    }
    if lo[0] > hi[0] {
        return None;
    }
    let s = ssbvb_voxel::model::cell_size(lod.level);
    let corner = |c: [u32; 3]| DVec3::from(c.map(|v| v as f64 * s - 1.0));
    Some((corner(lo), corner(hi.map(|v| v + 1))))
}

impl GpuScene {
    /// Uploads every LOD of every object's asset and the triangle meshes, the streams cut
    /// into the largest chunks the device binds ([`StreamChunks::for_device`]).
    pub fn new(ctx: &GpuContext, scene: Scene) -> Result<Self, PassError> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        Self::with_chunks(ctx, scene, StreamChunks::for_device(limit))
    }

    /// [`Self::new`] with the streams split into bindings of the given sizes (smaller
    /// chunks let tests cross chunk boundaries with small scenes).
    pub fn with_chunks(
        ctx: &GpuContext,
        scene: Scene,
        chunks: StreamChunks,
    ) -> Result<Self, PassError> {
        Self::build(ctx, scene, chunks, None, &[])
    }

    /// [`Self::new`] with room for the voxels of the objects in `rooms` to change on the GPU
    /// ([`GpuScene::set_object_levels`]).
    pub fn with_dynamic(
        ctx: &GpuContext,
        scene: Scene,
        rooms: &[DynamicRoom],
    ) -> Result<Self, PassError> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        Self::build(ctx, scene, StreamChunks::for_device(limit), None, rooms)
    }

    /// Uploads the scene under a GPU memory budget: levels up to
    /// [`crate::streaming::PINNED_LEVEL`] whole, the finer ones page by page as rays need
    /// them (`streaming.rs`). An error names the smallest budget that holds the parts that
    /// never leave (lookup trees down to the pages, pinned levels, proxies) and one page.
    pub fn streamed(
        ctx: &GpuContext,
        scene: Scene,
        options: &StreamingOptions,
    ) -> Result<Self, PassError> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        Self::build(
            ctx,
            scene,
            StreamChunks::for_device(limit),
            Some(options),
            &[],
        )
    }

    /// [`Self::streamed`] with the given stream chunks.
    pub fn streamed_with_chunks(
        ctx: &GpuContext,
        scene: Scene,
        chunks: StreamChunks,
        options: &StreamingOptions,
    ) -> Result<Self, PassError> {
        Self::build(ctx, scene, chunks, Some(options), &[])
    }

    fn build(
        ctx: &GpuContext,
        scene: Scene,
        chunks: StreamChunks,
        streaming: Option<&StreamingOptions>,
        rooms: &[DynamicRoom],
    ) -> Result<Self, PassError> {
        if let Some(r) = rooms.iter().find(|r| r.object >= scene.objects.len()) {
            return Err(PassError::BadScene(format!(
                "dynamic room for object {}, the scene has {}",
                r.object,
                scene.objects.len()
            )));
        }
        if streaming.is_some() && !rooms.is_empty() {
            return Err(PassError::BadScene(
                "dynamic objects cannot be paged under a GPU budget".into(),
            ));
        }
        let mut dynamic: Vec<DynamicObject> = Vec::new();
        if !(4..=30).contains(&chunks.word_bits)
            || !(4..=28).contains(&chunks.node_bits)
            || !(4..=28).contains(&chunks.octree_bits)
        {
            return Err(PassError::BadScene(format!(
                "unusable stream chunks {chunks:?}"
            )));
        }
        let mut lods: Vec<LodInfo> = Vec::new();
        let mut colors: Vec<u32> = Vec::new();
        let mut normals: Vec<u16> = Vec::new();
        let mut nodes: Vec<u32> = Vec::new();
        let mut proxy_v: Vec<[f32; 4]> = Vec::new();
        let mut proxy_i: Vec<u32> = Vec::new();
        let mut lod_base = Vec::new();
        let mut lod_bounds = Vec::new();
        let mut proxies = Vec::new();
        let mut memory = Vec::new();
        let mut paged = PagedLayoutBuilder::new();
        let mut proxy_bytes = 0u64;
        for (oi, obj) in scene.objects.iter().enumerate() {
            if obj.asset.lods.is_empty() {
                return Err(PassError::BadScene(
                    "an object's asset has no LOD levels".into(),
                ));
            }
            lod_base.push(checked_u32(lods.len(), "LOD count")?);
            let room = rooms.iter().find(|r| r.object == oi);
            if room.is_some() {
                dynamic.push(DynamicObject {
                    object: oi,
                    levels: Vec::new(),
                });
            }
            let mut ranges = Vec::new();
            let mut mem = ObjectMemory::default();
            for lod in &obj.asset.lods {
                let l = &lod.lookup;
                if l.level != lod.level || l.voxel_count() != lod.point_cloud.voxels.len() as u64 {
                    return Err(PassError::BadScene(format!(
                        "level {}: the lookup (level {}, {} voxels) does not match the point \
                         cloud ({} voxels)",
                        lod.level,
                        l.level,
                        l.voxel_count(),
                        lod.point_cloud.voxels.len()
                    )));
                }
                if room.is_some() && colors.len() % 2 == 1 {
                    // Normals go two per word: a dynamic level starts on a word.
                    colors.push(0);
                    normals.push(0);
                }
                let mut info = LodInfo {
                    level: lod.level,
                    depth: l.depth,
                    voxel_offset: checked_u32(colors.len(), "voxel count")?,
                    node_offset: checked_u32(nodes.len() / NODE_WORDS, "lookup nodes")?,
                    object: checked_u32(lod_base.len() - 1, "object count")?,
                    chunk_bits: chunks.word_bits,
                    node_chunk_bits: chunks.node_bits,
                    page_base: NO_PAGES,
                    first_page_node: 0,
                };
                lod_bounds.push(match room {
                    // Whatever a dynamic level's voxels become, they stay in the object box.
                    Some(_) => Some((DVec3::splat(-1.0), DVec3::ONE)),
                    None => voxel_bounds(lod),
                });
                if streaming.is_some() && lod.level > PINNED_LEVEL {
                    // Paged: the tree down to the page nodes; leaves and voxels by demand.
                    let file = streaming.and_then(|o| o.page_files.get(oi).cloned().flatten());
                    let entries = match &file {
                        Some(f) => {
                            if f.voxels(lod.level) != lod.point_cloud.voxels.len() as u64 {
                                return Err(PassError::BadScene(format!(
                                    "{}: level {} has {} voxels, the asset {}",
                                    f.path().display(),
                                    lod.level,
                                    f.voxels(lod.level),
                                    lod.point_cloud.voxels.len()
                                )));
                            }
                            f.pages(lod.level).to_vec()
                        }
                        None => ssbvb_voxel::cache::page_index(&lod.point_cloud.voxels),
                    };
                    let need = crate::streaming::pool_need(l, &entries);
                    let (page_base, first) =
                        paged.push_lod(oi, lod.level, entries, need, &mut nodes)?;
                    info.voxel_offset = 0;
                    info.page_base = page_base;
                    info.first_page_node = first;
                } else {
                    // Only what the GPU reads: the cell is implied by the lookup (id =
                    // Morton rank), texture coordinates are not read by any pass.
                    colors.extend(lod.point_cloud.voxels.iter().map(|v| v.color));
                    normals.extend(
                        lod.point_cloud
                            .voxels
                            .iter()
                            .map(|v| (v.z_normal >> 16) as u16),
                    );
                    nodes.extend_from_slice(&l.nodes);
                    if let (Some(r), Some(d)) = (room, dynamic.last_mut()) {
                        let n = lod.point_cloud.voxels.len();
                        let node_count = l.nodes.len() / NODE_WORDS;
                        let (vcap, ncap) = (r.capacity(n), r.capacity(node_count));
                        colors.resize(info.voxel_offset as usize + vcap, 0);
                        normals.resize(colors.len(), 0);
                        nodes.resize((info.node_offset as usize + ncap) * NODE_WORDS, 0);
                        d.levels.push(DynamicLevel {
                            voxel_offset: info.voxel_offset,
                            voxel_capacity: checked_u32(vcap, "voxel count")?,
                            node_offset: info.node_offset,
                            node_capacity: checked_u32(ncap, "lookup nodes")?,
                            voxels: checked_u32(n, "voxel count")?,
                            nodes: checked_u32(node_count, "lookup nodes")?,
                        });
                    }
                }
                checked_u32(nodes.len(), "lookup size")?;
                lods.push(info);
                let lod_memory = ObjectMemory::of_lod(lod);
                mem.add(&lod_memory);
                let proxy = lod_memory.proxy_bytes;
                if let Some(o) = streaming.filter(|o| lod.level > o.proxy_level) {
                    // Borrowed: see `StreamingOptions::proxy_level`.
                    let borrowed = ranges[o.proxy_level as usize];
                    ranges.push(borrowed);
                    continue;
                }
                proxy_bytes += proxy;
                let boxed = room.map(|_| dynamic::object_box());
                let proxy_mesh = boxed.as_ref().unwrap_or(&lod.proxy);
                ranges.push(ProxyRange {
                    first_index: checked_u32(proxy_i.len(), "proxy indices")?,
                    index_count: checked_u32(proxy_mesh.triangles.len() * 3, "proxy indices")?,
                    base_vertex: checked_u32(proxy_v.len(), "proxy vertices")? as i32,
                });
                proxy_v.extend(proxy_mesh.positions.iter().map(|p| [p[0], p[1], p[2], 1.0]));
                proxy_i.extend(proxy_mesh.triangles.iter().flatten());
            }
            proxies.push(ranges);
            memory.push(mem);
        }
        let pools = match streaming {
            Some(o) => Some(plan_pools(
                o.budget_bytes,
                &paged,
                &mut nodes,
                &mut colors,
                &mut normals,
                proxy_bytes + (lods.len() * std::mem::size_of::<LodInfo>()) as u64,
            )?),
            None => None,
        };
        let voxel_slots = colors.len() as u64;
        let d = &ctx.device;
        let ro = |binding: u32| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX
                | wgpu::ShaderStages::FRAGMENT
                | wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX
                | wgpu::ShaderStages::FRAGMENT
                | wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }];
        entries.extend((1..SCENE_STORAGE_BUFFERS as u32).map(ro));
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: SCENE_STORAGE_BUFFERS as u32,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        });
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &entries,
        });
        let frame_buffer = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let total_instances: usize = scene.objects.iter().map(|o| o.instances.len()).sum();
        if total_instances > ssbvb_voxel::instance_bvh::MAX_GPU_ITEMS {
            return Err(PassError::TooLarge(format!(
                "{total_instances} instances; the GPU's instance hierarchy holds at most {}",
                ssbvb_voxel::instance_bvh::MAX_GPU_ITEMS
            )));
        }
        let instance_buffer = Self::instance_buffer(ctx, total_instances.max(1));
        let bvh_buffer = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instance bvh"),
            size: ((2 * total_instances).max(1) * std::mem::size_of::<GpuBvhNode>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // A scene without voxel objects (volumes only) still binds one LOD record: a
        // shader's array binding must hold an element.
        if lods.is_empty() {
            lods.push(bytemuck::Zeroable::zeroed());
        }
        let lod_buffer = storage(ctx, "lods", bytemuck::cast_slice(&lods))?;
        if normals.len() % 2 == 1 {
            normals.push(0);
        }
        let words = 4usize << chunks.word_bits;
        let color_buffers = chunked(
            ctx,
            "voxel colours",
            bytemuck::cast_slice(&colors),
            words,
            COLOR_CHUNKS,
        )?;
        drop(colors);
        let normal_buffers = chunked(
            ctx,
            "voxel normals",
            bytemuck::cast_slice(&normals),
            words,
            NORMAL_CHUNKS,
        )?;
        drop(normals);
        let lookup_buffers = chunked(
            ctx,
            "lookup nodes",
            bytemuck::cast_slice(&nodes),
            (4 * NODE_WORDS) << chunks.node_bits,
            NODE_CHUNKS,
        )?;
        drop(nodes);
        let streaming = match (streaming, pools) {
            (Some(options), Some(p)) => Some(Streaming::new(
                ctx,
                paged,
                scene.objects.iter().map(|o| o.asset.clone()).collect(),
                options,
                p.node_pool_start,
                p.voxel_pool_start,
                p.slots,
                p.blocks,
                p.fixed_bytes,
            )),
            _ => None,
        };
        let feedback_dummy = streaming.is_none().then(|| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("page feedback (unused)"),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        });
        let feedback = streaming
            .as_ref()
            .map(|s| &s.feedback)
            .or(feedback_dummy.as_ref())
            .expect("one of the two exists");
        let proxy_vertices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("proxy vertices"),
            contents: bytemuck::cast_slice(if proxy_v.is_empty() {
                &[[0f32; 4]][..]
            } else {
                &proxy_v
            }),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let proxy_indices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("proxy indices"),
            contents: bytemuck::cast_slice(if proxy_i.is_empty() {
                &[0u32; 4][..]
            } else {
                &proxy_i
            }),
            usage: wgpu::BufferUsages::INDEX,
        });
        let meshes = scene
            .triangles
            .iter()
            .map(|t| {
                let verts: Vec<f32> = t
                    .positions
                    .iter()
                    .zip(t.normals.iter().chain(std::iter::repeat(&[0.0, 1.0, 0.0])))
                    .flat_map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]])
                    .collect();
                GpuTriangleMesh {
                    vertices: d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("mesh vertices"),
                        contents: bytemuck::cast_slice(&verts),
                        usage: wgpu::BufferUsages::VERTEX,
                    }),
                    indices: d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("mesh indices"),
                        contents: bytemuck::cast_slice(&t.indices),
                        usage: wgpu::BufferUsages::INDEX,
                    }),
                    index_count: t.indices.len() as u32,
                    uniform: d.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("mesh uniform"),
                        size: std::mem::size_of::<MeshUniform>() as u64,
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                }
            })
            .collect();
        let bind_group = Self::make_bind_group(
            ctx,
            &layout,
            &[&frame_buffer, &instance_buffer, &lod_buffer]
                .into_iter()
                .chain(&color_buffers)
                .chain(&normal_buffers)
                .chain(&lookup_buffers)
                .chain([&bvh_buffer, feedback])
                .collect::<Vec<_>>(),
        );
        Ok(Self {
            scene,
            chunks,
            layout,
            bind_group,
            frame_buffer,
            instance_buffer,
            bvh_buffer,
            lod_buffer,
            color_buffers,
            normal_buffers,
            lookup_buffers,
            proxy_vertices,
            proxy_indices,
            lod_base,
            lod_bounds,
            proxies,
            meshes,
            visible: Vec::new(),
            memory,
            streaming,
            dynamic,
            _feedback_dummy: feedback_dummy,
            voxel_slots,
            camera: Camera::default(),
            screen: (1, 1),
        })
    }

    fn instance_buffer(ctx: &GpuContext, n: usize) -> wgpu::Buffer {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: (n * std::mem::size_of::<InstanceUniform>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn make_bind_group(
        ctx: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        bufs: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        let entries: Vec<_> = bufs
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout,
            entries: &entries,
        })
    }

    /// Culls instances against the view frustum, chooses each one's LOD (under a budget at
    /// most the streaming level cap) and writes the frame constants and the visible
    /// instances for `camera` at `screen`.
    pub fn update(&mut self, ctx: &GpuContext, camera: &Camera, screen: (u32, u32)) {
        self.camera = *camera;
        self.screen = screen;
        let eye = camera.position;
        let frame = frame_uniform(camera, screen, &self.scene.light);
        // Under a budget too small for the view's pages: no instance finer than this.
        let cap = self
            .streaming
            .as_ref()
            .and_then(Streaming::level_cap)
            .unwrap_or(u32::MAX);
        let caps = crate::visibility::LevelCaps {
            level: cap,
            proxy: self
                .streaming
                .as_ref()
                .map_or(u32::MAX, Streaming::proxy_level),
        };
        let (visible, uniforms) = visible_instances(
            &self.scene,
            &self.lod_base,
            &self.proxies,
            camera,
            screen,
            caps,
        );
        let mut bvh = instance_bvh(&uniforms, &self.lod_bounds);
        if bvh.is_empty() && !uniforms.is_empty() {
            // Visible instances without voxels: a root that no ray enters (an empty box), so
            // no walk reads last frame's nodes.
            bvh.push(GpuBvhNode {
                lo: [1e37; 3],
                left: ssbvb_voxel::instance_bvh::LEAF,
                hi: [-1e37; 3],
                right: 0,
            });
        }
        if !bvh.is_empty() {
            ctx.queue
                .write_buffer(&self.bvh_buffer, 0, bytemuck::cast_slice(&bvh));
        }
        let mut frame = frame;
        frame.misc[3] = visible.len() as f32;
        ctx.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&frame));
        if !uniforms.is_empty() {
            ctx.queue
                .write_buffer(&self.instance_buffer, 0, bytemuck::cast_slice(&uniforms));
        }
        for (mesh, t) in self.meshes.iter().zip(&self.scene.triangles) {
            let model = DAffine3 {
                matrix3: t.transform.matrix3,
                translation: t.transform.translation - eye,
            };
            let nm = DMat4::from_mat3(model.matrix3.inverse().transpose());
            let u = MeshUniform {
                model: mat(DMat4::from(model)),
                normal_matrix: mat(nm),
                color: t.color,
                pad: [0.0; 4],
            };
            ctx.queue
                .write_buffer(&mesh.uniform, 0, bytemuck::bytes_of(&u));
        }
        self.visible = visible;
    }

    /// The streams the page cache writes into.
    fn stream_buffers(&self) -> StreamBuffers<'_> {
        StreamBuffers {
            colors: &self.color_buffers,
            normals: &self.normal_buffers,
            nodes: &self.lookup_buffers,
            word_chunk_bytes: 4u64 << self.chunks.word_bits,
            node_chunk_bytes: (4 * NODE_WORDS as u64) << self.chunks.node_bits,
        }
    }

    /// Under a budget: reads the page feedback of earlier frames that is ready and streams
    /// the pages it asks for (never waits; [`Self::sync_streaming`] does). Called by the
    /// renderer before each frame.
    pub fn stream_pages(&mut self, ctx: &GpuContext) -> Result<(), PassError> {
        self.service(ctx, false)
    }

    /// Under a budget: waits for the GPU, then reads the latest frame's page feedback and
    /// streams what it asks for (offline rendering converges frame by frame with it).
    pub fn sync_streaming(&mut self, ctx: &GpuContext) -> Result<(), PassError> {
        self.service(ctx, true)
    }

    fn service(&mut self, ctx: &GpuContext, wait: bool) -> Result<(), PassError> {
        let Some(mut s) = self.streaming.take() else {
            return Ok(());
        };
        let r = s.service(ctx, &self.stream_buffers(), wait);
        self.streaming = Some(s);
        r
    }

    /// Under a budget: evicts every page (tests and the viewer's budget changes).
    pub fn evict_all_pages(&mut self, ctx: &GpuContext) {
        if let Some(mut s) = self.streaming.take() {
            s.evict_all(ctx, &self.stream_buffers());
            self.streaming = Some(s);
        }
    }

    /// What the page cache did (`None` without a budget).
    pub fn streaming_stats(&self) -> Option<&StreamingStats> {
        self.streaming.as_ref().map(Streaming::stats)
    }

    /// Pages refused so far under a budget, with why.
    pub fn page_errors(&self) -> Vec<String> {
        self.streaming
            .as_ref()
            .map(Streaming::errors)
            .unwrap_or_default()
    }

    /// Records the start of a frame's commands (clears the page feedback).
    pub fn begin_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(s) = &mut self.streaming {
            s.begin_frame(encoder);
        }
    }

    /// Records the end of a frame's commands (copies the page feedback out).
    pub fn end_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(s) = &mut self.streaming {
            s.end_frame(encoder);
        }
    }

    /// After the frame's submission: maps the feedback copy without waiting.
    pub fn after_submit(&mut self) {
        if let Some(s) = &mut self.streaming {
            s.after_submit();
        }
    }

    /// Whether `level` of the scene's objects is paged (under a budget, above the pinned
    /// levels).
    pub fn is_paged(&self, level: u32) -> bool {
        self.streaming.is_some() && level > PINNED_LEVEL
    }

    /// How many unique-voxel keys an instance at `level` of `object` needs: its level's
    /// voxels, or under a budget (where its hits may come from coarser LODs and its voxel
    /// ids are pool indices) every voxel index of the scene.
    pub fn voxel_key_range(&self, object: usize, level: u32) -> u64 {
        if self.is_paged(level) {
            self.voxel_slots
        } else {
            self.scene.objects[object].asset.lods[level as usize]
                .point_cloud
                .voxels
                .len() as u64
        }
    }

    /// Visible instances of the current frame per chosen level.
    pub fn lod_histogram(&self) -> std::collections::BTreeMap<u32, usize> {
        let mut h = std::collections::BTreeMap::new();
        for v in &self.visible {
            *h.entry(v.level).or_insert(0) += 1;
        }
        h
    }

    /// Bytes of the shared voxel buffers (all objects).
    pub fn total_memory(&self) -> u64 {
        self.memory.iter().map(ObjectMemory::total).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::StreamChunks;

    #[test]
    fn chunks_follow_the_device_binding_size() {
        // lavapipe and WebGPU's default: 128 MiB.
        assert_eq!(StreamChunks::for_device(128 << 20), StreamChunks::default());
        let big = StreamChunks::for_device(u64::from(u32::MAX));
        assert_eq!(
            (big.word_bits, big.node_bits, big.octree_bits),
            (29, 28, 28)
        );
        let odd = StreamChunks::for_device(100 << 20);
        assert_eq!(
            (odd.word_bits, odd.node_bits, odd.octree_bits),
            (24, 23, 23)
        );
        let tiny = StreamChunks::for_device(0);
        assert_eq!(
            (tiny.word_bits, tiny.node_bits, tiny.octree_bits),
            (4, 4, 4)
        );
    }
}
