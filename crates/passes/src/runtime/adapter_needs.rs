//! What a pipeline needs from an adapter, gathered from its passes' registrations and its
//! resources (see [`ssbvb_gpu::requirements`] for why this is checked before a device
//! exists).

use ssbvb_gpu::requirements::{
    Requirements, color_attachment_bytes, max_bind_groups, max_color_attachment_bytes_per_sample,
    max_storage_buffers_per_shader_stage,
};
use ssbvb_gpu::scene::SceneBindings;
use ssbvb_gpu::wgpu;
use ssbvb_graph::{Access, PassStage, ResolvedPipeline, ResourceDesc, ResourceUsage, SlotClass};

use crate::kinds::registration;

use wgpu::DownlevelFlags as F;

/// What `pipeline` needs from an adapter for a scene whose streams take one binding each
/// (the least any scene binds: what can be checked before the scene is loaded;
/// [`pipeline_requirements_for`] for a given scene).
pub fn pipeline_requirements(pipeline: &ResolvedPipeline) -> Requirements {
    pipeline_requirements_for(pipeline, &SceneBindings::SMALLEST)
}

/// What `pipeline` needs from an adapter to draw a scene bound as `scene`: the scene's
/// bindings, each live pass kind's needs, and every texture resource's format with its
/// usages.
pub fn pipeline_requirements_for(
    pipeline: &ResolvedPipeline,
    scene: &SceneBindings,
) -> Requirements {
    let scene_storage = u64::from(scene.max_storage_buffers());
    let mut req = Requirements::default();
    // The scene's group 0 is visible to the vertex, fragment and compute stages.
    req.need_flags(
        F::VERTEX_STORAGE | F::FRAGMENT_STORAGE,
        "the scene's bindings (group 0)",
    );
    req.need_limit(
        max_storage_buffers_per_shader_stage(scene_storage),
        "the scene's bindings (group 0)",
    );
    for pass in &pipeline.passes {
        let who = format!("pass `{}` ({})", pass.name, pass.kind.name());
        let Some(reg) = registration(&pass.kind) else {
            continue;
        };
        let n = reg.needs;
        if pass.kind.stage() == PassStage::Compute {
            req.need_flags(F::COMPUTE_SHADERS, &who);
        }
        if !n.flags.is_empty() {
            req.need_flags(n.flags, &who);
        }
        req.need_limit(
            max_storage_buffers_per_shader_stage(scene_storage + n.storage_buffers),
            &who,
        );
        req.need_limit(max_bind_groups(n.bind_groups), &who);
        if let Some(l) = n.limit {
            req.need_limit(l, &who);
        }
        // The colour attachments a render pass writes together.
        let formats: Vec<wgpu::TextureFormat> = pass
            .kind
            .slots()
            .iter()
            .filter(|s| {
                s.access == Access::Write && matches!(s.class, SlotClass::ColorAttachment(_))
            })
            .filter_map(|s| pass.resource_of(s.name))
            .filter_map(|r| match pipeline.resources[r].desc {
                ResourceDesc::Texture { format, .. } => Some(format.to_wgpu()),
                _ => None,
            })
            .collect();
        if !formats.is_empty() {
            req.need_limit(
                max_color_attachment_bytes_per_sample(color_attachment_bytes(&formats)),
                &who,
            );
        }
    }
    for r in &pipeline.resources {
        let (ResourceDesc::Texture { format, .. }, ResourceUsage::Texture(usage)) =
            (&r.desc, r.usage)
        else {
            continue;
        };
        let format = format.to_wgpu();
        let who = format!("resource `{}`", r.name);
        let fallbacks: &[wgpu::TextureFormat] = match format {
            // `frame::texture_format` takes this when the device lacks the feature.
            wgpu::TextureFormat::Depth32FloatStencil8 => {
                &[wgpu::TextureFormat::Depth24PlusStencil8]
            }
            _ => &[],
        };
        req.need_format(
            format,
            usage | wgpu::TextureUsages::COPY_SRC,
            &who,
            fallbacks,
        );
    }
    // Reading the stencil back (voxel pixels in `render --json`, the viewer's overlay)
    // copies a depth-stencil texture to a buffer; without that capability (GL) a
    // stencil-tested draw counts instead (`count_stencil`), so it is not a need.
    req
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_pipeline_needs_compute_indirect_and_read_only_depth() {
        let src = include_str!("../../../../assets/pipelines/ssbvb_unique.ron");
        let p = ssbvb_graph::resolve_str(src, "ssbvb_unique.ron").unwrap();
        let req = pipeline_requirements(&p);
        let flags = req
            .downlevel
            .iter()
            .fold(F::empty(), |acc, (f, _)| acc | *f);
        for f in [F::COMPUTE_SHADERS, F::INDIRECT_EXECUTION, F::VERTEX_STORAGE] {
            assert!(flags.contains(f), "{f:?} missing from {:#?}", req.downlevel);
        }
        // What GL lacks has a fallback: the smoothing copies the depth first, and the
        // stencil is counted by a stencil-tested draw.
        for f in [
            F::READ_ONLY_DEPTH_STENCIL,
            F::DEPTH_TEXTURE_AND_BUFFER_COPIES,
        ] {
            assert!(!flags.contains(f), "{f:?} in {:#?}", req.downlevel);
        }
        let entry = req
            .formats
            .iter()
            .find(|n| n.what == "resource `entry`")
            .expect("the entry texture is a need");
        assert_eq!(entry.format, wgpu::TextureFormat::Rgba32Float);
        assert!(
            entry
                .usages
                .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        );
        let storage = req
            .limits
            .iter()
            .find(|(n, _)| n.name == "max_storage_buffers_per_shader_stage")
            .unwrap();
        // 5 of the scene in compute (group 0: instances, the hierarchy, the page feedback,
        // one word and one node chunk) and 3 of the filter (the SSBVB, the draw, its own
        // words): WebGPU's default of 8.
        assert_eq!(storage.0.at_least, 8, "{storage:?}");
        assert!(storage.1.contains("RayMarchFilter"), "{storage:?}");
        // A scene that needs two word chunks needs one more.
        let two = SceneBindings {
            word_chunks: 2,
            node_chunks: 1,
        };
        let req = pipeline_requirements_for(&p, &two);
        let (n, _) = req
            .limits
            .iter()
            .find(|(n, _)| n.name == "max_storage_buffers_per_shader_stage")
            .unwrap();
        assert_eq!(n.at_least, 9);
    }

    /// Every bundled pipeline's render passes fit WebGPU's default 32 bytes of colour
    /// attachments per sample (the G-buffer writers take exactly 32: albedo packed in a
    /// `u32` 4, shading normal 8, position 16, geometric normal 4), and the need names the
    /// widest pass. The sum is wgpu's own byte costs: an `Rgba8Unorm` albedo would cost 8
    /// and make it 36.
    #[test]
    fn colour_attachments_fit_webgpu_default_bytes_per_sample() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/pipelines");
        let mut checked = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let text = std::fs::read_to_string(&path).unwrap();
            let p = ssbvb_graph::resolve_str(&text, &path.display().to_string()).unwrap();
            let req = pipeline_requirements(&p);
            let (need, who) = req
                .limits
                .iter()
                .find(|(n, _)| n.name == "max_color_attachment_bytes_per_sample")
                .unwrap();
            assert!(
                need.at_least <= 32,
                "{}: {} bytes ({who})",
                path.display(),
                need.at_least
            );
            if text.contains("gbuffer_geometric_normal") {
                assert_eq!(need.at_least, 32, "{}: {who}", path.display());
            }
            checked += 1;
        }
        assert!(checked >= 10, "{checked}");
        let rgba8 = [
            wgpu::TextureFormat::Rgba8Unorm,
            wgpu::TextureFormat::Rgba16Float,
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureFormat::Rg16Float,
        ];
        assert_eq!(color_attachment_bytes(&rgba8), 36);
    }
}
