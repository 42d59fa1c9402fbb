//! Gathering a scene's streams on the CPU before they are uploaded: the LOD table, the
//! voxel colours and normals, the lookup trees' nodes (whole, or down to the page nodes
//! under a budget), the dynamic objects' rooms and the proxy meshes; then the group-0
//! layout, the proxy and triangle-mesh buffers.

use crate::InitBuffer;
use glam::DVec3;
use ssbvb_voxel::asset::LodLevel;
use ssbvb_voxel::lookup::NODE_WORDS;

use super::description::{Scene, TriangleObject};
use super::dynamic::{self, DynamicLevel, DynamicObject, DynamicRoom};
use super::layout::{GpuTriangleMesh, LodInfo, MeshUniform, NO_PAGES, ObjectMemory, ProxyRange};
use super::pools::{StreamChunks, checked_u32};
use super::streaming::{PINNED_LEVEL, PagedLayoutBuilder, StreamingOptions, pool_need};
use crate::{ResourceError, wgpu};

/// Refuses what cannot be uploaded before anything is gathered.
pub(super) fn check_inputs(
    scene: &Scene,
    chunks: StreamChunks,
    streaming: Option<&StreamingOptions>,
    rooms: &[DynamicRoom],
) -> Result<(), ResourceError> {
    if let Some(r) = rooms.iter().find(|r| r.object >= scene.objects.len()) {
        return Err(ResourceError::BadScene(format!(
            "dynamic room for object {}, the scene has {}",
            r.object,
            scene.objects.len()
        )));
    }
    if streaming.is_some() && !rooms.is_empty() {
        return Err(ResourceError::BadScene(
            "dynamic objects cannot be paged under a GPU budget".into(),
        ));
    }
    if !(4..=30).contains(&chunks.word_bits)
        || !(4..=28).contains(&chunks.node_bits)
        || !(4..=28).contains(&chunks.octree_bits)
    {
        return Err(ResourceError::BadScene(format!(
            "unusable stream chunks {chunks:?}"
        )));
    }
    Ok(())
}

/// The scene's streams as they will be uploaded.
#[derive(Default)]
pub(super) struct SceneStreams {
    /// The LOD table.
    pub lods: Vec<LodInfo>,
    /// Voxel colours, one word per voxel.
    pub colors: Vec<u32>,
    /// Voxel normals, 16-bit octahedral.
    pub normals: Vec<u16>,
    /// The lookup trees' nodes.
    pub nodes: Vec<u32>,
    /// Proxy vertices (object space, vec4).
    pub proxy_v: Vec<[f32; 4]>,
    /// Proxy indices.
    pub proxy_i: Vec<u32>,
    /// Per object, the index of its level 0 in the LOD table.
    pub lod_base: Vec<u32>,
    /// Per LOD-table entry, the object-space box of its voxels.
    pub lod_bounds: Vec<Option<(DVec3, DVec3)>>,
    /// `proxies[object][level]`.
    pub proxies: Vec<Vec<ProxyRange>>,
    /// GPU memory per object.
    pub memory: Vec<ObjectMemory>,
    /// The paged levels' layout (empty without a budget).
    pub paged: PagedLayoutBuilder,
    /// Bytes of the proxies drawn (borrowed proxies counted once).
    pub proxy_bytes: u64,
    /// Objects with a room for GPU-built levels.
    pub dynamic: Vec<DynamicObject>,
}

impl SceneStreams {
    /// Gathers every object's levels.
    pub fn gather(
        scene: &Scene,
        chunks: StreamChunks,
        streaming: Option<&StreamingOptions>,
        rooms: &[DynamicRoom],
    ) -> Result<Self, ResourceError> {
        let mut s = Self {
            paged: PagedLayoutBuilder::new(),
            ..Self::default()
        };
        for (oi, obj) in scene.objects.iter().enumerate() {
            if obj.asset.lods.is_empty() {
                return Err(ResourceError::BadScene(
                    "an object's asset has no LOD levels".into(),
                ));
            }
            s.lod_base.push(checked_u32(s.lods.len(), "LOD count")?);
            let room = rooms.iter().find(|r| r.object == oi);
            if room.is_some() {
                s.dynamic.push(DynamicObject {
                    object: oi,
                    levels: Vec::new(),
                });
            }
            let mut ranges = Vec::new();
            let mut mem = ObjectMemory::default();
            for lod in &obj.asset.lods {
                let lod_memory = ObjectMemory::of_lod(lod);
                mem.add(&lod_memory);
                s.push_lod(oi, lod, chunks, streaming, room)?;
                if let Some(o) = streaming.filter(|o| lod.level > o.proxy_level) {
                    // Borrowed: see `StreamingOptions::proxy_level`.
                    let borrowed = ranges[o.proxy_level as usize];
                    ranges.push(borrowed);
                    continue;
                }
                s.proxy_bytes += lod_memory.proxy_bytes;
                ranges.push(s.push_proxy(lod, room.is_some())?);
            }
            s.proxies.push(ranges);
            s.memory.push(mem);
        }
        Ok(s)
    }

    /// Adds one level of object `oi`: its LOD-table entry, and its voxels and nodes (whole,
    /// or the tree down to the page nodes when it is paged), with the room of a dynamic
    /// object.
    fn push_lod(
        &mut self,
        oi: usize,
        lod: &LodLevel,
        chunks: StreamChunks,
        streaming: Option<&StreamingOptions>,
        room: Option<&DynamicRoom>,
    ) -> Result<(), ResourceError> {
        let l = &lod.lookup;
        if l.level != lod.level || l.voxel_count() != lod.point_cloud.voxels.len() as u64 {
            return Err(ResourceError::BadScene(format!(
                "level {}: the lookup (level {}, {} voxels) does not match the point \
                 cloud ({} voxels)",
                lod.level,
                l.level,
                l.voxel_count(),
                lod.point_cloud.voxels.len()
            )));
        }
        if room.is_some() && self.colors.len() % 2 == 1 {
            // Normals go two per word: a dynamic level starts on a word.
            self.colors.push(0);
            self.normals.push(0);
        }
        let mut info = LodInfo {
            level: lod.level,
            depth: l.depth,
            voxel_offset: checked_u32(self.colors.len(), "voxel count")?,
            node_offset: checked_u32(self.nodes.len() / NODE_WORDS, "lookup nodes")?,
            object: checked_u32(self.lod_base.len() - 1, "object count")?,
            chunk_bits: chunks.word_bits,
            node_chunk_bits: chunks.node_bits,
            page_base: NO_PAGES,
            first_page_node: 0,
        };
        self.lod_bounds.push(match room {
            // Whatever a dynamic level's voxels become, they stay in the object box.
            Some(_) => Some((DVec3::splat(-1.0), DVec3::ONE)),
            None => voxel_bounds(lod),
        });
        match streaming {
            Some(options) if lod.level > PINNED_LEVEL => {
                let (page_base, first) = self.push_paged(oi, lod, options)?;
                info.voxel_offset = 0;
                info.page_base = page_base;
                info.first_page_node = first;
            }
            _ => self.push_whole(lod, &info, room)?,
        }
        checked_u32(self.nodes.len(), "lookup size")?;
        self.lods.push(info);
        Ok(())
    }

    /// A paged level: the tree down to the page nodes; leaves and voxels come by demand.
    /// Returns the level's first page and first page node.
    fn push_paged(
        &mut self,
        oi: usize,
        lod: &LodLevel,
        options: &StreamingOptions,
    ) -> Result<(u32, u32), ResourceError> {
        let entries = match options.page_files.get(oi).cloned().flatten() {
            Some(f) => {
                if f.voxels(lod.level) != lod.point_cloud.voxels.len() as u64 {
                    return Err(ResourceError::BadScene(format!(
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
        let need = pool_need(&lod.lookup, &entries);
        self.paged
            .push_lod(oi, lod.level, entries, need, &mut self.nodes)
    }

    /// A level resident whole, with the room of a dynamic object after it.
    fn push_whole(
        &mut self,
        lod: &LodLevel,
        info: &LodInfo,
        room: Option<&DynamicRoom>,
    ) -> Result<(), ResourceError> {
        let l = &lod.lookup;
        // Only what the GPU reads: the cell is implied by the lookup (id = Morton rank),
        // texture coordinates are not read by any pass.
        let voxels = &lod.point_cloud.voxels;
        self.colors.extend(voxels.iter().map(|v| v.color));
        self.normals
            .extend(voxels.iter().map(|v| (v.z_normal >> 16) as u16));
        self.nodes.extend_from_slice(&l.nodes);
        if let (Some(r), Some(d)) = (room, self.dynamic.last_mut()) {
            let n = voxels.len();
            let node_count = l.nodes.len() / NODE_WORDS;
            let (vcap, ncap) = (r.capacity(n), r.capacity(node_count));
            self.colors.resize(info.voxel_offset as usize + vcap, 0);
            self.normals.resize(self.colors.len(), 0);
            self.nodes
                .resize((info.node_offset as usize + ncap) * NODE_WORDS, 0);
            d.levels.push(DynamicLevel {
                voxel_offset: info.voxel_offset,
                voxel_capacity: checked_u32(vcap, "voxel count")?,
                node_offset: info.node_offset,
                node_capacity: checked_u32(ncap, "lookup nodes")?,
                voxels: checked_u32(n, "voxel count")?,
                nodes: checked_u32(node_count, "lookup nodes")?,
            });
        }
        Ok(())
    }

    /// Appends a level's proxy mesh (the object box for a dynamic object) and returns its
    /// range.
    fn push_proxy(&mut self, lod: &LodLevel, dynamic: bool) -> Result<ProxyRange, ResourceError> {
        let boxed = dynamic.then(dynamic::object_box);
        let proxy_mesh = boxed.as_ref().unwrap_or(&lod.proxy);
        let range = ProxyRange {
            first_index: checked_u32(self.proxy_i.len(), "proxy indices")?,
            index_count: checked_u32(proxy_mesh.triangles.len() * 3, "proxy indices")?,
            base_vertex: checked_u32(self.proxy_v.len(), "proxy vertices")? as i32,
        };
        self.proxy_v
            .extend(proxy_mesh.positions.iter().map(|p| [p[0], p[1], p[2], 1.0]));
        self.proxy_i.extend(proxy_mesh.triangles.iter().flatten());
        Ok(range)
    }
}

/// The object-space box of a level's voxels (their cells' union), `None` when it has none.
fn voxel_bounds(lod: &LodLevel) -> Option<(DVec3, DVec3)> {
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

/// The proxy vertex and index buffers (one dummy element each when empty: a buffer is
/// never zero-sized).
pub(super) fn proxy_buffers(
    d: &wgpu::Device,
    proxy_v: &[[f32; 4]],
    proxy_i: &[u32],
) -> (wgpu::Buffer, wgpu::Buffer) {
    let vertices = d.init_buffer(&wgpu::util::BufferInitDescriptor {
        label: Some("proxy vertices"),
        contents: bytemuck::cast_slice(if proxy_v.is_empty() {
            &[[0f32; 4]][..]
        } else {
            proxy_v
        }),
        // STORAGE: the compute prepass reads them (EmptySpaceCompute).
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
    });
    let indices = d.init_buffer(&wgpu::util::BufferInitDescriptor {
        label: Some("proxy indices"),
        contents: bytemuck::cast_slice(if proxy_i.is_empty() {
            &[0u32; 4][..]
        } else {
            proxy_i
        }),
        usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE,
    });
    (vertices, indices)
}

/// The triangle objects' vertex (position, normal), index and uniform buffers.
pub(super) fn triangle_meshes(
    d: &wgpu::Device,
    triangles: &[TriangleObject],
) -> Vec<GpuTriangleMesh> {
    triangles
        .iter()
        .map(|t| {
            let verts: Vec<f32> = t
                .positions
                .iter()
                .zip(t.normals.iter().chain(std::iter::repeat(&[0.0, 1.0, 0.0])))
                .flat_map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]])
                .collect();
            GpuTriangleMesh {
                vertices: d.init_buffer(&wgpu::util::BufferInitDescriptor {
                    label: Some("mesh vertices"),
                    contents: bytemuck::cast_slice(&verts),
                    usage: wgpu::BufferUsages::VERTEX,
                }),
                indices: d.init_buffer(&wgpu::util::BufferInitDescriptor {
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
        .collect()
}
