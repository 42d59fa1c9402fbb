//! The scene on the GPU: every LOD of every asset in shared buffers, proxy meshes,
//! triangle meshes, and the per-frame constants and visible instances (group 0 of every
//! pass; WGSL declarations in `shaders/common.inc.wgsl`).

use glam::{DAffine3, DMat4, DVec3};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::lookup::NODE_WORDS;

use crate::{GpuContext, ResourceError, wgpu};

mod description;
mod dynamic;
mod gpu_level;
mod layout;
pub mod page_cache;
mod pools;
pub mod streaming;
mod tile_lists;
mod upload;
pub mod visibility;

pub use crate::scene_bindings::{
    FIRST_STREAM_BINDING, LOD_WORDS, SCENE_STREAMS_INCLUDE, SceneBindings, chunk_switch, chunks_for,
};
pub use description::{LodPolicy, Scene, TriangleObject, VolumeObject, VoxelObject};
pub use dynamic::{DynamicLevel, DynamicObject, DynamicRoom};
pub use dynamic::{copy_words, copy_words_from_chunks};
pub use gpu_level::GpuLevel;
pub use layout::*;
pub use pools::{MAX_STREAM_CHUNKS, StreamChunks};
pub use streaming::{StreamingOptions, StreamingStats};
pub use tile_lists::{LIST_TILE_PX, LIST_WALK, MAX_FILLS_PER_TILE, MAX_TILE_LIST};
pub use visibility::{DEFAULT_LOD_HYSTERESIS, choose_level, choose_level_held, frame_uniform};

use pools::{checked_u32, chunked, plan_pools};
use streaming::{PINNED_LEVEL, StreamBuffers, Streaming};
use upload::{SceneStreams, check_inputs, proxy_buffers, triangle_meshes};
use visibility::{instance_bvh, mat, visible_instances};

/// The scene on the GPU.
pub struct GpuScene {
    /// The CPU scene (transforms are read each frame).
    pub scene: Scene,
    /// How the streams are split over bindings (passes that upload their own large
    /// buffers split them alike).
    pub chunks: StreamChunks,
    /// How many bindings the streams take in group 0 (the WGSL of every pass that binds
    /// group 0 is generated for them: [`crate::shaders::source_for`]).
    pub bindings: SceneBindings,
    /// Group 0 layout shared by every pass.
    pub layout: wgpu::BindGroupLayout,
    /// Group 0 of the current frame.
    pub bind_group: wgpu::BindGroup,
    /// Per-frame constants.
    pub frame_buffer: wgpu::Buffer,
    /// Visible instances (room for every instance of the scene).
    pub instance_buffer: wgpu::Buffer,
    /// The hierarchy over the visible instances' boxes (room for every instance), then the
    /// screen tiles' instance lists (grown, and group 0 bound again, when a frame's lists
    /// need more room).
    pub bvh_buffer: wgpu::Buffer,
    /// Whether frames get screen tiles' instance lists (`tile_lists`; on by default; off:
    /// every ray walks the hierarchy, for comparison).
    pub instance_lists: bool,
    /// Words of the lists in the current frame (0: none), for reports.
    pub instance_list_words: usize,
    /// The word stream: the LOD table, the voxel colours (linear RGBA8, one word per
    /// voxel) from word [`Self::color_word_base`], the voxel normals (16-bit octahedral,
    /// two per word) from word [`Self::normal_word_base`]; in bindings of
    /// `2^chunks.word_bits` words.
    pub word_buffers: Vec<wgpu::Buffer>,
    /// First word of the colours in the word stream.
    pub color_word_base: u64,
    /// First word of the normals in the word stream.
    pub normal_word_base: u64,
    /// The lookup trees' nodes (12 bytes each), in bindings of `2^chunks.node_bits` nodes.
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
    /// How far past a threshold, in levels, Auto LOD waits before drawing an instance
    /// coarser than in the frame before ([`DEFAULT_LOD_HYSTERESIS`]; 0: every frame
    /// chooses afresh, as [`choose_level`] does).
    pub lod_hysteresis: f64,
    /// Levels finer than Auto LOD's choice to draw each `Auto` instance at (set by the
    /// renderer before [`GpuScene::update`] from a temporal pass's `lod_bias`; 0: none).
    pub lod_bias: u32,
    /// By scene index, the level each instance was drawn at in the last frame.
    held_levels: Vec<Option<u32>>,
    /// GPU memory per object (the whole asset, as uploaded without a budget).
    pub memory: Vec<ObjectMemory>,
    /// The page cache under a budget (`None`: every level resident).
    pub streaming: Option<streaming::Streaming>,
    /// Objects whose voxels change on the GPU, with their room in the streams.
    pub dynamic: Vec<DynamicObject>,
    /// Page feedback binding (a small unused buffer without a budget).
    _feedback_dummy: Option<wgpu::Buffer>,
    /// Voxel indices of the colour stream (for unique-voxel keys under a budget).
    voxel_slots: u64,
    /// The camera of the current frame.
    pub camera: Camera,
    /// Sub-pixel jitter of the next frames, in pixels (a temporal pass's; set by the
    /// renderer before [`GpuScene::update`]).
    pub jitter: [f64; 2],
    /// Screen size of the current frame.
    pub screen: (u32, u32),
}

/// The scene's word and node streams, uploaded.
struct UploadedStreams {
    words: Vec<wgpu::Buffer>,
    color_word_base: u64,
    normal_word_base: u64,
    nodes: Vec<wgpu::Buffer>,
}

/// Uploads the word stream (the LOD table, the voxel colours, the normals two per word) and
/// the lookup nodes, each cut into the chunks the scene binds.
fn upload_streams(
    ctx: &GpuContext,
    chunks: StreamChunks,
    lods: &[LodInfo],
    colors: Vec<u32>,
    mut normals: Vec<u16>,
    nodes: Vec<u32>,
) -> Result<UploadedStreams, ResourceError> {
    if normals.len() % 2 == 1 {
        normals.push(0);
    }
    let color_word_base = (lods.len() * LOD_WORDS) as u64;
    let normal_word_base = color_word_base + colors.len() as u64;
    let words = chunked(
        ctx,
        "LOD table, voxel colours and normals",
        &[
            bytemuck::cast_slice(lods),
            bytemuck::cast_slice(&colors),
            bytemuck::cast_slice(&normals),
        ],
        4usize << chunks.word_bits,
    )?;
    checked_u32(
        (normal_word_base + normals.len() as u64 / 2) as usize,
        "words of the LOD table, colours and normals",
    )?;
    drop((colors, normals));
    let nodes = chunked(
        ctx,
        "lookup nodes",
        &[bytemuck::cast_slice(&nodes)],
        (4 * NODE_WORDS) << chunks.node_bits,
    )?;
    Ok(UploadedStreams {
        words,
        color_word_base,
        normal_word_base,
        nodes,
    })
}

impl GpuScene {
    /// Uploads every LOD of every object's asset and the triangle meshes, the streams cut
    /// into the largest chunks the device binds ([`StreamChunks::for_device`]).
    pub fn new(ctx: &GpuContext, scene: Scene) -> Result<Self, ResourceError> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        Self::with_chunks(ctx, scene, StreamChunks::for_device(limit))
    }

    /// [`Self::new`] with the streams split into bindings of the given sizes (smaller
    /// chunks let tests cross chunk boundaries with small scenes).
    pub fn with_chunks(
        ctx: &GpuContext,
        scene: Scene,
        chunks: StreamChunks,
    ) -> Result<Self, ResourceError> {
        Self::build(ctx, scene, chunks, None, &[])
    }

    /// [`Self::new`] with room for the voxels of the objects in `rooms` to change on the GPU
    /// ([`GpuScene::set_object_levels`]).
    pub fn with_dynamic(
        ctx: &GpuContext,
        scene: Scene,
        rooms: &[DynamicRoom],
    ) -> Result<Self, ResourceError> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        Self::build(ctx, scene, StreamChunks::for_device(limit), None, rooms)
    }

    /// Uploads the scene under a GPU memory budget: levels up to
    /// [`streaming::PINNED_LEVEL`] whole, the finer ones page by page as rays need
    /// them (`streaming.rs`). An error names the smallest budget that holds the parts that
    /// never leave (lookup trees down to the pages, pinned levels, proxies) and one page.
    pub fn streamed(
        ctx: &GpuContext,
        scene: Scene,
        options: &StreamingOptions,
    ) -> Result<Self, ResourceError> {
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
    ) -> Result<Self, ResourceError> {
        Self::build(ctx, scene, chunks, Some(options), &[])
    }

    fn build(
        ctx: &GpuContext,
        scene: Scene,
        chunks: StreamChunks,
        streaming: Option<&StreamingOptions>,
        rooms: &[DynamicRoom],
    ) -> Result<Self, ResourceError> {
        check_inputs(&scene, chunks, streaming, rooms)?;
        let mut streams = SceneStreams::gather(&scene, chunks, streaming, rooms)?;
        let pools = match streaming {
            Some(o) => Some(plan_pools(
                o.budget_bytes,
                &streams.paged,
                &mut streams.nodes,
                &mut streams.colors,
                &mut streams.normals,
                streams.proxy_bytes + (streams.lods.len() * std::mem::size_of::<LodInfo>()) as u64,
            )?),
            None => None,
        };
        let SceneStreams {
            mut lods,
            colors,
            normals,
            nodes,
            proxy_v,
            proxy_i,
            lod_base,
            lod_bounds,
            proxies,
            memory,
            paged,
            dynamic,
            ..
        } = streams;
        let voxel_slots = colors.len() as u64;
        let d = &ctx.device;
        let frame_buffer = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let total_instances: usize = scene.objects.iter().map(|o| o.instances.len()).sum();
        if total_instances > ssbvb_voxel::instance_bvh::MAX_GPU_ITEMS {
            return Err(ResourceError::TooLarge(format!(
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
        let streams = upload_streams(ctx, chunks, &lods, colors, normals, nodes)?;
        let bindings = SceneBindings {
            word_chunks: streams.words.len() as u32,
            node_chunks: streams.nodes.len() as u32,
        };
        let layout = bindings.layout(d);
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
        let (proxy_vertices, proxy_indices) = proxy_buffers(d, &proxy_v, &proxy_i);
        let meshes = triangle_meshes(d, &scene.triangles);
        let bind_group = crate::kernels::bind_buffers(
            &ctx.device,
            "scene",
            &layout,
            &[&frame_buffer, &instance_buffer, &bvh_buffer, feedback]
                .into_iter()
                .chain(&streams.words)
                .chain(&streams.nodes)
                .collect::<Vec<_>>(),
        );
        Ok(Self {
            scene,
            chunks,
            bindings,
            layout,
            bind_group,
            frame_buffer,
            instance_buffer,
            bvh_buffer,
            instance_lists: true,
            instance_list_words: 0,
            word_buffers: streams.words,
            color_word_base: streams.color_word_base,
            normal_word_base: streams.normal_word_base,
            lookup_buffers: streams.nodes,
            proxy_vertices,
            proxy_indices,
            lod_base,
            lod_bounds,
            proxies,
            meshes,
            visible: Vec::new(),
            lod_hysteresis: DEFAULT_LOD_HYSTERESIS,
            lod_bias: 0,
            held_levels: Vec::new(),
            memory,
            streaming,
            dynamic,
            _feedback_dummy: feedback_dummy,
            voxel_slots,
            camera: Camera::default(),
            jitter: [0.0; 2],
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

    /// Culls instances against the view frustum, chooses each one's LOD (under a budget at
    /// most the streaming level cap) and writes the frame constants and the visible
    /// instances for `camera` at `screen`.
    pub fn update(&mut self, ctx: &GpuContext, camera: &Camera, screen: (u32, u32)) {
        self.camera = *camera;
        self.screen = screen;
        let eye = camera.position;
        let frame =
            visibility::jittered_frame_uniform(camera, screen, &self.scene.light, self.jitter);
        // Under a budget too small for the view's pages: no instance finer than this.
        let cap = self
            .streaming
            .as_ref()
            .and_then(Streaming::level_cap)
            .unwrap_or(u32::MAX);
        let caps = visibility::LevelCaps {
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
            &visibility::View {
                camera,
                screen,
                lod_bias: self.lod_bias,
            },
            caps,
            &self.held_levels,
            self.lod_hysteresis,
        );
        let instances = self.scene.objects.iter().map(|o| o.instances.len()).sum();
        self.held_levels.clear();
        self.held_levels.resize(instances, None);
        for v in &visible {
            self.held_levels[v.scene_index as usize] = Some(v.level);
        }
        let mut bvh = instance_bvh(&uniforms, &self.lod_bounds);
        let mut frame = frame;
        frame.shine_near_far_count[3] = visible.len() as f32;
        frame.prepass[0] = u32::from(!visible.iter().any(|v| v.back_faces || v.camera_inside));
        let lists = if self.instance_lists {
            tile_lists::tile_lists(&bvh, &frame, 8 * bvh.len())
        } else {
            Vec::new()
        };
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
        let lists = self.fit_instance_lists(ctx, bvh.len(), lists);
        // Lists start after the nodes (two vec4s each); 0 is never a list's start.
        let lists_at = if lists.is_empty() { 0 } else { 2 * bvh.len() };
        if !bvh.is_empty() {
            ctx.queue
                .write_buffer(&self.bvh_buffer, 0, bytemuck::cast_slice(&bvh));
        }
        if !lists.is_empty() {
            let at = (bvh.len() * std::mem::size_of::<GpuBvhNode>()) as u64;
            ctx.queue
                .write_buffer(&self.bvh_buffer, at, bytemuck::cast_slice(&lists));
        }
        self.instance_list_words = lists.len();
        frame.streams = [
            self.chunks.word_bits,
            self.color_word_base as u32,
            self.normal_word_base as u32,
            lists_at as u32,
        ];
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

    /// `lists` if the hierarchy's buffer can hold them after `nodes` nodes, grown (and
    /// group 0 bound again) where it must be; none where the device's limits do not allow
    /// that buffer (rays then walk the hierarchy).
    fn fit_instance_lists(&mut self, ctx: &GpuContext, nodes: usize, lists: Vec<u32>) -> Vec<u32> {
        let need = (nodes * std::mem::size_of::<GpuBvhNode>() + 4 * lists.len()) as u64;
        if lists.is_empty() || need <= self.bvh_buffer.size() {
            return lists;
        }
        let limits = ctx.device.limits();
        let cap = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        // A quarter more than asked, so a moving camera does not grow it every frame.
        let size = (need + need / 4).next_multiple_of(16).min(cap);
        if need > size {
            return Vec::new();
        }
        self.bvh_buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instance bvh"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let feedback = self.page_feedback();
        self.bind_group = crate::kernels::bind_buffers(
            &ctx.device,
            "scene",
            &self.layout,
            &[
                &self.frame_buffer,
                &self.instance_buffer,
                &self.bvh_buffer,
                feedback,
            ]
            .into_iter()
            .chain(&self.word_buffers)
            .chain(&self.lookup_buffers)
            .collect::<Vec<_>>(),
        );
        lists
    }

    /// The streams the page cache writes into.
    fn stream_buffers(&self) -> StreamBuffers<'_> {
        StreamBuffers {
            words: &self.word_buffers,
            color_word_base: self.color_word_base,
            normal_word_base: self.normal_word_base,
            nodes: &self.lookup_buffers,
            word_chunk_bytes: 4u64 << self.chunks.word_bits,
            node_chunk_bytes: (4 * NODE_WORDS as u64) << self.chunks.node_bits,
        }
    }

    /// The buffer group 0 binds as the page feedback (binding 3; a small unused one
    /// without a budget): its size is the size of a pass's own feedback buffer (a
    /// fragment shader that marches sets its bits there and merges them in compute).
    pub fn page_feedback(&self) -> &wgpu::Buffer {
        self.streaming
            .as_ref()
            .map(|s| &s.feedback)
            .or(self._feedback_dummy.as_ref())
            .expect("one of the two exists")
    }

    /// Under a budget: reads the page feedback of earlier frames that is ready and streams
    /// the pages it asks for (never waits; [`Self::sync_streaming`] does). Called by the
    /// renderer before each frame.
    pub fn stream_pages(&mut self, ctx: &GpuContext) -> Result<(), ResourceError> {
        self.service(ctx, false)
    }

    /// Under a budget: waits for the GPU, then reads the latest frame's page feedback and
    /// streams what it asks for (offline rendering converges frame by frame with it).
    pub fn sync_streaming(&mut self, ctx: &GpuContext) -> Result<(), ResourceError> {
        self.service(ctx, true)
    }

    fn service(&mut self, ctx: &GpuContext, wait: bool) -> Result<(), ResourceError> {
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

/// Dynamic objects: levels built on the GPU copied into their rooms.
impl GpuScene {
    /// The room of dynamic object `object`, if it is one.
    pub fn dynamic_object(&self, object: usize) -> Option<&DynamicObject> {
        self.dynamic.iter().find(|d| d.object == object)
    }

    /// Replaces the voxels of dynamic object `object` by `levels` (`levels[l]` is level
    /// `l`, as `ssbvb_gpu_build::lod_build::GpuLodBuilder::build` returns them), all on the
    /// GPU. An error when the object is not dynamic, the levels do not match its asset's,
    /// or a level outgrows its room (naming the room needed).
    pub fn set_object_levels(
        &mut self,
        ctx: &GpuContext,
        object: usize,
        levels: &[GpuLevel],
    ) -> Result<(), ResourceError> {
        let chunks = self.chunks;
        let Some(dynamic) = self.dynamic.iter_mut().find(|d| d.object == object) else {
            return Err(ResourceError::BadScene(format!(
                "object {object} was not uploaded with room for dynamic voxels"
            )));
        };
        if levels.len() != dynamic.levels.len()
            || levels.iter().enumerate().any(|(l, g)| g.level != l as u32)
        {
            return Err(ResourceError::BadScene(format!(
                "object {object}: {} new levels for {} levels",
                levels.len(),
                dynamic.levels.len()
            )));
        }
        for (g, room) in levels.iter().zip(&dynamic.levels) {
            if g.count > room.voxel_capacity || g.node_count > room.node_capacity {
                return Err(ResourceError::TooLarge(format!(
                    "object {object} level {}: {} voxels and {} lookup nodes, its room holds \
                     {} and {} (upload it with more growth)",
                    g.level, g.count, g.node_count, room.voxel_capacity, room.node_capacity
                )));
            }
        }
        let color_words = 1u64 << chunks.word_bits;
        let node_words = (NODE_WORDS as u64) << chunks.node_bits;
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("dynamic object"),
            });
        for (g, room) in levels.iter().zip(dynamic.levels.iter_mut()) {
            let n = u64::from(g.count);
            let at = u64::from(room.voxel_offset);
            copy_words(
                &mut enc,
                &g.packed,
                0,
                &self.word_buffers,
                color_words,
                self.color_word_base + at,
                n,
            );
            copy_words(
                &mut enc,
                &g.packed_normals,
                0,
                &self.word_buffers,
                color_words,
                self.normal_word_base + at / 2,
                n.div_ceil(2),
            );
            copy_words(
                &mut enc,
                &g.nodes,
                0,
                &self.lookup_buffers,
                node_words,
                NODE_WORDS as u64 * u64::from(room.node_offset),
                NODE_WORDS as u64 * u64::from(g.node_count),
            );
            room.voxels = g.count;
            room.nodes = g.node_count;
        }
        ctx.submit("scene: dynamic level copy", [enc.finish()]);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::StreamChunks;

    #[test]
    fn a_lod_table_entry_is_lod_words_words() {
        assert_eq!(std::mem::size_of::<super::LodInfo>(), 4 * super::LOD_WORDS);
    }

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
