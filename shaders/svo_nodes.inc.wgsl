// The scene's sparse voxel octrees as the octree ray casters read them (octree_ray_cast.wgsl,
// esvo_ray_cast.wgsl; uploaded and bound by octree_ray_cast.rs for both): group 1,
// bindings 0–8. The includer declares its further bindings from 9 on.
//
// Octree layout (ssbvb_voxel::svo::Svo): nodes level by level, node i of level l being
// entry i of LOD l's point cloud; `child_mask` bit c = x | y << 1 | z << 2 set when child c
// exists, existing children stored from `first_child` in increasing c. Every object's
// octree is in the `svo_nodes_*` chunks (its child indices shifted by where it starts);
// `svo_level_offsets[object * SVO_STRIDE + l]` is the first node of its level l (then one
// past its last level), so a node's voxel id is `node - offset[level]`. The finest level's
// nodes are not stored (no traversal reads them: a hit is found in its parent's mask).

// Level offsets per object: levels 0..=16 and the end (octree_ray_cast.rs SVO_STRIDE).
const SVO_STRIDE: u32 = 18u;

struct SvoNode {
    child_mask: u32,
    first_child: u32,
}

// The nodes, split over bindings of 2^NODE_CHUNK_BITS nodes (octree_ray_cast.rs). A
// pipeline binds only the chunks its octrees fill: `svo_node` (svo_node_read.inc.wgsl,
// which the pass generates for that count; the file holds the eight-chunk form) reads no
// other, and the layout leaves the rest out.
override NODE_CHUNK_BITS: u32 = 24u;
@group(1) @binding(0) var<storage, read> svo_nodes_0: array<SvoNode>;
@group(1) @binding(1) var<storage, read> svo_nodes_1: array<SvoNode>;
@group(1) @binding(2) var<storage, read> svo_nodes_2: array<SvoNode>;
@group(1) @binding(3) var<storage, read> svo_nodes_3: array<SvoNode>;
@group(1) @binding(4) var<storage, read> svo_nodes_4: array<SvoNode>;
@group(1) @binding(5) var<storage, read> svo_nodes_5: array<SvoNode>;
@group(1) @binding(6) var<storage, read> svo_nodes_6: array<SvoNode>;
@group(1) @binding(7) var<storage, read> svo_nodes_7: array<SvoNode>;
@group(1) @binding(8) var<storage, read> svo_level_offsets: array<u32>;

//#include "svo_node_read.inc.wgsl"
