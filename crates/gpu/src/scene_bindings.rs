//! Group 0 as one scene binds it: the frame uniform, the instances, the instance
//! hierarchy, the page feedback, and the scene's two streams in as many bindings as their
//! data needs (WebGPU's default limit is 8 storage buffers per shader stage, so nothing is
//! bound that the scene does not use).
//!
//! The streams:
//!
//! - the *word* stream: the LOD table ([`LOD_WORDS`] words per entry), then the voxel
//!   colours (one word per voxel), then the voxel normals (two 16-bit normals per word);
//!   the frame uniform's `streams` field holds its chunk size and where colours and normals
//!   begin;
//! - the lookup-node stream ([`NODE_WORDS`](ssbvb_voxel::lookup::NODE_WORDS) words per
//!   node).
//!
//! Each is split into bindings of at most the device's storage binding size. The WGSL that
//! declares these bindings and reads the streams (`scene_streams.inc.wgsl`, included by
//! `common.inc.wgsl`) is generated here for the number of bindings the scene has, because
//! a binding a shader names must be in the layout even where the code that reads it never
//! runs.

use std::fmt::Write;

use crate::wgpu;

/// Words of one LOD-table entry in the word stream (`LodInfo`, 36 bytes; the scene's tests
/// hold the two equal).
pub const LOD_WORDS: usize = 9;

/// Group 0 binding of the first word-stream chunk (the node chunks follow the word ones).
pub const FIRST_STREAM_BINDING: u32 = 4;

/// Name of the generated include that declares the scene's stream bindings.
pub const SCENE_STREAMS_INCLUDE: &str = "scene_streams.inc.wgsl";

/// How many bindings each of the scene's streams takes in group 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SceneBindings {
    /// Bindings of the word stream (LOD table, colours, normals).
    pub word_chunks: u32,
    /// Bindings of the lookup-node stream.
    pub node_chunks: u32,
}

impl SceneBindings {
    /// One binding per stream: every scene whose streams fit one binding each, and what a
    /// pipeline is checked against before a scene exists.
    pub const SMALLEST: Self = Self {
        word_chunks: 1,
        node_chunks: 1,
    };

    /// Storage buffers group 0 binds to `stage` (only compute shaders see the page
    /// feedback, which the filter writes).
    pub fn storage_buffers(&self, stage: wgpu::ShaderStages) -> u32 {
        let feedback = u32::from(stage.contains(wgpu::ShaderStages::COMPUTE));
        2 + feedback + self.word_chunks + self.node_chunks
    }

    /// The most storage buffers group 0 binds to any one stage.
    pub fn max_storage_buffers(&self) -> u32 {
        self.storage_buffers(wgpu::ShaderStages::COMPUTE)
    }

    /// Group 0's layout: the frame uniform (0), instances (1), the instance hierarchy (2),
    /// the page feedback (3, compute only, read-write), then the word and node chunks.
    pub fn layout(&self, d: &wgpu::Device) -> wgpu::BindGroupLayout {
        let all =
            wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let buffer = |binding: u32, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let read_only = wgpu::BufferBindingType::Storage { read_only: true };
        let mut entries = vec![
            buffer(0, all, wgpu::BufferBindingType::Uniform),
            buffer(1, all, read_only),
            buffer(2, all, read_only),
            buffer(
                3,
                wgpu::ShaderStages::COMPUTE,
                wgpu::BufferBindingType::Storage { read_only: false },
            ),
        ];
        let streams = self.word_chunks + self.node_chunks;
        entries.extend(
            (FIRST_STREAM_BINDING..FIRST_STREAM_BINDING + streams)
                .map(|b| buffer(b, all, read_only)),
        );
        d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &entries,
        })
    }

    /// The WGSL of `scene_streams.inc.wgsl` for these bindings: the chunk declarations and
    /// `scene_word` / `lookup_node`, which pick the chunk of an index over a whole stream.
    pub fn wgsl(&self) -> String {
        let mut s =
            String::from("// Generated for this scene's bindings (ssbvb-gpu scene_bindings.rs).\n");
        let first_node = FIRST_STREAM_BINDING + self.word_chunks;
        for i in 0..self.word_chunks {
            let b = FIRST_STREAM_BINDING + i;
            let _ = writeln!(
                s,
                "@group(0) @binding({b}) var<storage, read> scene_words_{i}: array<u32>;"
            );
        }
        for i in 0..self.node_chunks {
            let b = first_node + i;
            let _ = writeln!(
                s,
                "@group(0) @binding({b}) var<storage, read> lookup_nodes_{i}: array<LookupNode>;"
            );
        }
        s.push_str("\n// Word `w` of the word stream.\nfn scene_word(w: u32) -> u32 {\n");
        s.push_str(&chunk_switch(
            self.word_chunks,
            "frame.streams.x",
            "w",
            "scene_words",
        ));
        s.push_str("}\n\n// Lookup node `n` (index over all LODs).\n");
        s.push_str("fn lookup_node(lod: LodInfo, n: u32) -> LookupNode {\n");
        s.push_str(&chunk_switch(
            self.node_chunks,
            "lod.node_chunk_bits",
            "n",
            "lookup_nodes",
        ));
        s.push_str("}\n");
        s
    }
}

/// The body of an accessor: element `index` of a stream split over `chunks` bindings named
/// `{name}_{i}` of `2^bits` elements each (`bits` a WGSL expression).
pub fn chunk_switch(chunks: u32, bits: &str, index: &str, name: &str) -> String {
    if chunks == 1 {
        return format!("    return {name}_0[{index}];\n");
    }
    let mut s =
        format!("    let i = {index} & ((1u << {bits}) - 1u);\n    switch {index} >> {bits} {{\n");
    for c in 0..chunks - 1 {
        let _ = writeln!(s, "        case {c}u: {{ return {name}_{c}[i]; }}");
    }
    let _ = writeln!(
        s,
        "        default: {{ return {name}_{}[i]; }}\n    }}",
        chunks - 1
    );
    s
}

/// Bindings a stream of `bytes` bytes needs in chunks of `chunk_bytes` (at least one: an
/// empty stream still binds a small buffer).
pub fn chunks_for(bytes: u64, chunk_bytes: u64) -> u32 {
    bytes.div_ceil(chunk_bytes).max(1) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_chunk_reads_directly_and_more_switch_on_the_chunk_bits() {
        let one = SceneBindings::SMALLEST.wgsl();
        assert!(one.contains("return scene_words_0[w];"), "{one}");
        assert!(!one.contains("switch"), "{one}");
        let three = SceneBindings {
            word_chunks: 3,
            node_chunks: 2,
        }
        .wgsl();
        assert!(three.contains("@group(0) @binding(6) var<storage, read> scene_words_2"));
        assert!(three.contains("@group(0) @binding(8) var<storage, read> lookup_nodes_1"));
        assert!(
            three.contains("case 1u: { return scene_words_1[i]; }"),
            "{three}"
        );
        assert!(
            three.contains("default: { return scene_words_2[i]; }"),
            "{three}"
        );
        assert!(
            three.contains("default: { return lookup_nodes_1[i]; }"),
            "{three}"
        );
    }

    #[test]
    fn storage_buffers_count_the_feedback_in_compute_only() {
        let b = SceneBindings {
            word_chunks: 2,
            node_chunks: 1,
        };
        assert_eq!(b.storage_buffers(wgpu::ShaderStages::VERTEX), 5);
        assert_eq!(b.storage_buffers(wgpu::ShaderStages::COMPUTE), 6);
        assert_eq!(b.max_storage_buffers(), 6);
        assert_eq!(chunks_for(0, 64), 1);
        assert_eq!(chunks_for(64, 64), 1);
        assert_eq!(chunks_for(65, 64), 2);
    }
}
