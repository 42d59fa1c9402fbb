//! Streams split over several bindings (`GpuScene::with_chunks`): no scene buffer may
//! exceed the device's storage binding size, so the word stream (LOD table, colours,
//! normals) and the lookup nodes are cut into chunks, as many as the data needs. Tiny chunks make a small model span every binding of every stream; each
//! technique that reads the streams must then draw exactly what it draws from one chunk
//! per stream (which other tests check against the CPU reference), and the image must not
//! be empty.

use glam::DVec3;
use ssbvb_gpu::scene::StreamChunks;
use ssbvb_voxel::camera::Camera;

const SIZE: (u32, u32) = (96, 72);

#[test]
fn every_chunk_of_every_stream_is_read_like_a_single_binding() {
    // A model with a colour per voxel (the bunny is one colour: a mixed-up colour chunk
    // would not show).
    let asset = ssbvb_tests::model_asset("chr_knight.vox", 6);
    let voxels: usize = asset.lods.iter().map(|l| l.point_cloud.voxels.len()).sum();
    let nodes: usize = asset.lods.iter().map(|l| l.lookup.node_count()).sum();
    // Chunks of a quarter to a half of the word stream (the LOD table, a word per colour,
    // half a word per normal): it then takes 3 or 4 bindings; the nodes take 2.
    let lods = asset.lods.len();
    let stream_words = ssbvb_gpu::scene::LOD_WORDS * lods + voxels + voxels.div_ceil(2);
    let word_bits = stream_words
        .div_ceil(4)
        .next_power_of_two()
        .trailing_zeros();
    let node_bits = nodes.div_ceil(2).next_power_of_two().trailing_zeros();
    // The octree baselines upload every level but the finest (the nodes it reads): over
    // 5 of its 8 bindings here (power-of-two chunks of this model give 5 or 10).
    let finest = asset.lods.last().unwrap().point_cloud.voxels.len();
    let octree_nodes = voxels - finest;
    let octree_bits = octree_nodes
        .div_ceil(8)
        .next_power_of_two()
        .trailing_zeros();
    assert!(
        octree_nodes > 4 << octree_bits,
        "{octree_nodes} octree nodes"
    );
    let small = StreamChunks {
        word_bits,
        node_bits,
        octree_bits,
    };
    assert!(
        stream_words > 2 << word_bits,
        "{stream_words} words, chunks of 2^{word_bits}"
    );
    assert!(
        nodes > 1 << node_bits,
        "{nodes} nodes, chunks of 2^{node_bits}"
    );
    let cam = Camera::new(DVec3::new(1.6, 0.9, 2.2), DVec3::new(0.0, 0.05, 0.0));
    let octree = include_str!("../../../assets/pipelines/octree.ron");
    let esvo = include_str!("../../../assets/pipelines/esvo.ron");
    // The casters' compute form reads the chunks through its own pipelines.
    let compute = |text: &str, kind: &str| {
        let from = format!("kind: {kind}(max_steps: 4096)");
        assert!(text.contains(&from), "{kind}: the bundled file changed");
        text.replace(
            &from,
            &format!("kind: {kind}(max_steps: 4096, compute: true)"),
        )
    };
    for (name, pipeline) in [
        (
            "ssbvb",
            include_str!("../../../assets/pipelines/ssbvb_unique.ron").to_string(),
        ),
        ("octree", octree.to_string()),
        ("octree compute", compute(octree, "OctreeRayCast")),
        ("esvo", esvo.to_string()),
        ("esvo compute", compute(esvo, "EsvoRayCast")),
        (
            "cube raster",
            include_str!("../../../assets/pipelines/cube_raster.ron").to_string(),
        ),
    ] {
        let pipeline = pipeline.as_str();
        let render = |chunks: StreamChunks| {
            // Level 6 and a coarser LOD, so LOD offsets into later chunks are exercised.
            [6, 4].map(|level| {
                let scene = ssbvb_tests::single_object_scene(asset.clone(), level);
                let f = ssbvb_tests::render_with_chunks(pipeline, scene, &cam, SIZE, chunks);
                let b = f.scene.bindings;
                assert_eq!(
                    (b.word_chunks as usize, b.node_chunks as usize),
                    (f.scene.word_buffers.len(), f.scene.lookup_buffers.len())
                );
                (
                    [f.read("gbuffer_albedo"), f.read("color")],
                    [b.word_chunks, b.node_chunks],
                )
            })
        };
        let one = render(StreamChunks::default());
        let split = render(small);
        for (level, (a, b)) in [6, 4].iter().zip(one.iter().zip(&split)) {
            assert_eq!(a.1, [1, 1], "{name} L{level}: default chunks");
            // The level-4 scene is a smaller stream in the same chunks.
            let words = if *level == 6 { 3..=4 } else { 2..=4 };
            assert!(
                words.contains(&b.1[0]) && b.1[1] == 2,
                "{name} L{level}: {:?}",
                b.1
            );
            let covered = a.0[0].chunks(4).filter(|p| p[3] > 0).count();
            assert!(covered > 500, "{name} L{level}: {covered} px");
            assert!(
                a.0 == b.0,
                "{name} L{level}: split streams draw another image"
            );
        }
    }
}
