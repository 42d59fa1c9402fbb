// Node `n` of the octrees split over eight bindings (svo_nodes.inc.wgsl). octree_ray_cast.rs
// generates this function for the chunks a scene's octrees fill; this is the eight-chunk
// form, which tools that read the files validate.
fn svo_node(n: u32) -> SvoNode {
    let i = n & ((1u << NODE_CHUNK_BITS) - 1u);
    switch n >> NODE_CHUNK_BITS {
        case 0u: { return svo_nodes_0[i]; }
        case 1u: { return svo_nodes_1[i]; }
        case 2u: { return svo_nodes_2[i]; }
        case 3u: { return svo_nodes_3[i]; }
        case 4u: { return svo_nodes_4[i]; }
        case 5u: { return svo_nodes_5[i]; }
        case 6u: { return svo_nodes_6[i]; }
        default: { return svo_nodes_7[i]; }
    }
}
