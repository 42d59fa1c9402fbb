//! The Rust mirrors of structs that WGSL reads or writes, as data: size and field offsets,
//! so `cargo xtask validate-shaders` compares them with naga's layout of the WGSL struct of
//! the same name (a field added on one side only, or a different alignment, fails there
//! with the struct and field named). Padding fields (`pad`, `_pad`, …) are not compared.

use crate::kinds::ray_march_filter::{DrawArgs, VoxelSlot};
use ssbvb_gpu::scene::{FrameUniform, GpuBvhNode, InstanceUniform, LodInfo, MeshUniform};
use ssbvb_voxel::asset::PackedVoxel;
use ssbvb_voxel::cube_list::Cube;
use ssbvb_voxel::svo::SvoNode;

/// The layout of one Rust struct mirrored in WGSL.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StructLayout {
    /// The WGSL struct's name.
    pub wgsl: &'static str,
    /// The Rust type's name.
    pub rust: &'static str,
    /// `size_of` in bytes.
    pub size: usize,
    /// Every field with its byte offset, in declaration order.
    pub fields: Vec<(&'static str, usize)>,
}

/// Whether a field is padding (not compared).
pub fn is_padding(name: &str) -> bool {
    name.trim_start_matches('_').starts_with("pad")
}

/// The layout of `$ty` under the WGSL name `$wgsl`. The destructuring makes the field list
/// exhaustive: a field added to the Rust struct and not listed here does not compile.
macro_rules! layout {
    ($wgsl:literal, $ty:ident { $($f:ident),* $(,)? }) => {{
        let _exhaustive = |v: $ty| {
            let $ty { $($f: _),* } = v;
        };
        StructLayout {
            wgsl: $wgsl,
            rust: stringify!($ty),
            size: std::mem::size_of::<$ty>(),
            fields: vec![$((stringify!($f), std::mem::offset_of!($ty, $f))),*],
        }
    }};
}

/// Every Rust struct whose bytes a shader reads or writes.
pub fn shared_structs() -> Vec<StructLayout> {
    vec![
        layout!(
            "Frame",
            FrameUniform {
                view_proj,
                inv_view_proj,
                view,
                proj,
                cam_right,
                cam_up,
                cam_forward,
                screen,
                light_dir,
                light_color,
                shine_near_far_count,
                jitter,
                streams,
                prepass
            }
        ),
        layout!(
            "Instance",
            InstanceUniform {
                object_to_world,
                object_to_view,
                world_to_object,
                camera_object,
                lod,
                level,
                flags,
                scene_index
            }
        ),
        layout!(
            "BvhNode",
            GpuBvhNode {
                lo,
                left,
                hi,
                right
            }
        ),
        layout!(
            "LodInfo",
            LodInfo {
                level,
                depth,
                voxel_offset,
                node_offset,
                object,
                chunk_bits,
                node_chunk_bits,
                page_base,
                first_page_node
            }
        ),
        layout!(
            "PackedVoxel",
            PackedVoxel {
                xy,
                z_normal,
                color,
                uv
            }
        ),
        layout!(
            "VoxelSlot",
            VoxelSlot {
                voxel,
                instance,
                pixel,
                t,
                face
            }
        ),
        layout!(
            "DrawArgs",
            DrawArgs {
                vertex_count,
                instance_count,
                first_vertex,
                first_instance
            }
        ),
        layout!(
            "Mesh",
            MeshUniform {
                model,
                normal_matrix,
                color,
                pad
            }
        ),
        layout!("Cube", Cube { xy, z_size }),
        layout!(
            "SvoNode",
            SvoNode {
                child_mask,
                first_child
            }
        ),
    ]
}

#[cfg(test)]
mod tests {
    #[test]
    fn layouts_are_taken_from_the_types() {
        let all = super::shared_structs();
        let slot = all.iter().find(|s| s.wgsl == "VoxelSlot").unwrap();
        assert_eq!(slot.size, 32);
        assert_eq!(
            slot.fields,
            vec![
                ("voxel", 0),
                ("instance", 16),
                ("pixel", 20),
                ("t", 24),
                ("face", 28)
            ]
        );
        assert!(
            super::is_padding("_pad") && super::is_padding("pad") && !super::is_padding("pixel")
        );
    }
}
