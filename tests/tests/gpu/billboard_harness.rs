//! What the billboard tests share (`billboards.rs`, `triangles.rs`): the pipeline text, the
//! SSBVB filled from the CPU reference, the passes recorded through the ordinary `Recorder`
//! without the passes before them, and the accuracy measures.

use std::path::PathBuf;

use glam::{DMat3, DVec3};
use ssbvb_gpu::scene::{GpuScene, LodPolicy, Scene};
use ssbvb_gpu::wgpu;
use ssbvb_graph::{BillboardMode, ResolvedPipeline};
use ssbvb_passes::PassNode;
use ssbvb_passes::kinds::billboards::{
    BillboardOptions, Billboards, DEFAULT_CULL_COS, Footprint, VoxelSlot,
};
use ssbvb_passes::kinds::triangles::Triangles;
use ssbvb_passes::runtime::recorder::Recorder;
use ssbvb_passes::runtime::resources::FrameResources;
use ssbvb_passes::{PassImpl, PassInit};
use ssbvb_tests::{ctx, reference_of};
use ssbvb_voxel::accuracy::{self, ErrorStats, GpuHit};
use ssbvb_voxel::camera::Camera;
use ssbvb_voxel::reference::ReferenceImage;

/// A pipeline whose G-buffer is written by `triangles` then `billboards` (the passes before
/// them exist so that the graph accepts the reads; tests may skip them).
pub(crate) fn pipeline_src(mode: BillboardMode, size_scale: f32, normal_format: &str) -> String {
    format!(
        r#"Pipeline(
  resources: {{
    "entry":            Texture(format: Rgba32Float, size: Screen),
    "prepass_depth":    Texture(format: Depth32Float, size: Screen),
    "ssbvb":            Buffer(layout: VoxelSlot, count: ScreenPixels),
    "billboard_draw":   Buffer(layout: DrawIndirect, count: Fixed(1)),
    "gbuffer_albedo":   Texture(format: R32Uint, size: Screen),
    "gbuffer_normal":   Texture(format: {normal_format}, size: Screen),
    "gbuffer_position": Texture(format: Rgba32Float, size: Screen),
    // Geometric normal (the face or triangle hit), octahedral-encoded.
    "gbuffer_geometric_normal": Texture(format: Rg16Float, size: Screen),
    "depth_stencil":    Texture(format: Depth32FloatStencil8, size: Screen),
  }},
  passes: [
    (name: "empty_space", kind: EmptySpacePrepass, writes: ["entry", "prepass_depth"]),
    (name: "filter", kind: RayMarchFilter(max_steps: 1024), reads: ["entry"],
     writes: ["ssbvb", "billboard_draw"]),
    (name: "triangles", kind: Triangles,
     writes: ["gbuffer_albedo", "gbuffer_normal", "gbuffer_position", "gbuffer_geometric_normal", "depth_stencil"]),
    (name: "billboards", kind: Billboards(mode: {mode:?}, size_scale: {size_scale}),
     reads: ["ssbvb", "billboard_draw"],
     writes: ["gbuffer_albedo", "gbuffer_normal", "gbuffer_position", "gbuffer_geometric_normal", "depth_stencil"],
     after: ["triangles"]),
  ],
  output: "gbuffer_albedo",
)"#
    )
}

/// The G-buffer read back (row-major, row 0 at the top).
pub(crate) struct GBuffer {
    pub width: u32,
    pub height: u32,
    pub albedo: Vec<[u8; 4]>,
    /// Shading normal.
    pub normal: Vec<[f32; 4]>,
    pub position: Vec<[f32; 4]>,
    /// Geometric normal, decoded.
    pub geometric: Vec<[f32; 3]>,
    /// Reversed-Z depth.
    pub depth: Vec<f32>,
    pub stencil: Vec<u8>,
}

use ssbvb_tests::f16_to_f32;

pub(crate) fn read_vec4(tex: &wgpu::Texture) -> Vec<[f32; 4]> {
    let data = ctx().read_texture(tex, wgpu::TextureAspect::All).unwrap();
    match tex.format() {
        wgpu::TextureFormat::Rgba32Float => bytemuck::pod_collect_to_vec::<u8, f32>(&data.bytes)
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        wgpu::TextureFormat::Rgba16Float => bytemuck::pod_collect_to_vec::<u8, u16>(&data.bytes)
            .chunks_exact(4)
            .map(|c| {
                c.iter()
                    .map(|&h| f16_to_f32(h))
                    .collect::<Vec<_>>()
                    .try_into()
                    .unwrap()
            })
            .collect(),
        f => panic!("unexpected format {f:?}"),
    }
}

impl GBuffer {
    /// Reads the G-buffer resources of `pipeline`.
    pub(crate) fn read(pipeline: &ResolvedPipeline, resources: &FrameResources) -> Self {
        let tex = |name: &str| &resources.texture(pipeline.resource(name).unwrap()).texture;
        let albedo_tex = tex("gbuffer_albedo");
        let albedo = ctx()
            .read_texture(albedo_tex, wgpu::TextureAspect::All)
            .unwrap()
            .bytes
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        let ds = tex("depth_stencil");
        let depth = if ds.format() == wgpu::TextureFormat::Depth32FloatStencil8 {
            ctx()
                .read_texture(ds, wgpu::TextureAspect::DepthOnly)
                .unwrap()
                .as_f32()
        } else {
            Vec::new()
        };
        let stencil = ctx()
            .read_texture(ds, wgpu::TextureAspect::StencilOnly)
            .unwrap()
            .bytes;
        Self {
            width: albedo_tex.width(),
            height: albedo_tex.height(),
            albedo,
            normal: read_vec4(tex("gbuffer_normal")),
            position: read_vec4(tex("gbuffer_position")),
            geometric: ssbvb_passes::measure::geometric_normals(
                &ctx()
                    .read_texture(tex("gbuffer_geometric_normal"), wgpu::TextureAspect::All)
                    .unwrap(),
            )
            .unwrap(),
            depth,
            stencil,
        }
    }

    /// Every value of every target is finite.
    pub(crate) fn assert_finite(&self) {
        for (i, (n, p)) in self.normal.iter().zip(&self.position).enumerate() {
            assert!(
                n.iter().chain(p).all(|v| v.is_finite()),
                "pixel {i}: normal {n:?} position {p:?}"
            );
        }
        if self.depth.is_empty() {
            // Depth24PlusStencil8 cannot be copied out: say that the check did not run.
            eprintln!(
                "depth range not checked: the adapter lacks DEPTH32FLOAT_STENCIL8, whose depth \
                 can be read back"
            );
            assert!(!ctx().has(wgpu::Features::DEPTH32FLOAT_STENCIL8));
            return;
        }
        assert_eq!(self.depth.len(), self.normal.len(), "one depth per pixel");
        assert!(
            self.depth
                .iter()
                .all(|d| d.is_finite() && (0.0..=1.0).contains(d))
        );
    }

    /// Whether billboards or triangles drew pixel `i`.
    pub(crate) fn covered(&self, i: usize) -> bool {
        self.albedo[i][3] > 0
    }

    /// Writes albedo and normal as PNGs under the system temp folder.
    pub(crate) fn write_pngs(&self, name: &str) {
        let dir = std::env::temp_dir().join("ssbvb_gbuffer");
        std::fs::create_dir_all(&dir).unwrap();
        let albedo: Vec<u8> = self.albedo.iter().flatten().copied().collect();
        let normal: Vec<u8> = self
            .normal
            .iter()
            .flat_map(|n| {
                let c = |v: f32| ((v * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0).round() as u8;
                [c(n[0]), c(n[1]), c(n[2]), if n[3] > 0.0 { 255 } else { 0 }]
            })
            .collect();
        let png = |suffix: &str, rgba: &[u8]| {
            let p: PathBuf = dir.join(format!("{name}_{suffix}.png"));
            ssbvb_gpu::readback::write_png_rgba8(&p, self.width, self.height, rgba).unwrap();
        };
        png("albedo", &albedo);
        png("normal", &normal);
    }
}

/// One SSBVB slot per pixel the reference hits, in pixel order (what the filter compacts).
pub(crate) fn slots_from_reference(
    scene: &Scene,
    gpu: &GpuScene,
    reference: &ReferenceImage,
) -> Vec<VoxelSlot> {
    // Flattened scene instance -> (object, level); visible instance index by scene index.
    let mut objects = Vec::new();
    for (oi, o) in scene.objects.iter().enumerate() {
        objects.extend(std::iter::repeat_n(oi, o.instances.len()));
    }
    reference
        .hits
        .iter()
        .enumerate()
        .filter_map(|(pixel, h)| {
            let h = h.as_ref()?;
            let visible = gpu
                .visible
                .iter()
                .position(|v| v.scene_index == h.instance)
                .expect("every instance the reference hits is visible on the GPU");
            let v = &gpu.visible[visible];
            assert_eq!(v.object, objects[h.instance as usize]);
            let mut voxel = scene.objects[v.object].asset.lods[v.level as usize]
                .point_cloud
                .voxels[h.voxel as usize];
            // A slot carries its voxel's level where a point cloud has texture coordinates.
            voxel.uv = v.level;
            let n = h.face_normal;
            let axis = (0..3)
                .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
                .unwrap();
            Some(VoxelSlot {
                voxel,
                instance: visible as u32,
                pixel: pixel as u32,
                t: h.t as f32,
                face: axis as u32 + if n[axis] > 0.0 { 3 } else { 0 },
            })
        })
        .collect()
}

/// Draws the G-buffer of `scene`: triangles when `triangles`, then billboards (when
/// `billboards` is given) over an SSBVB filled from the CPU reference. Returns the G-buffer
/// and the reference.
pub(crate) fn draw(
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    billboards: Option<BillboardOptions>,
    triangles: bool,
) -> (GBuffer, ReferenceImage) {
    let c = ctx();
    let mode = billboards.map_or(BillboardMode::Flat, |o| o.mode);
    let src = pipeline_src(mode, 1.0, "Rgba16Float");
    let pipeline = ssbvb_graph::resolve_str(&src, "billboards test").unwrap();
    let mut gpu = GpuScene::new(c, scene.clone()).unwrap();
    gpu.update(c, camera, size);
    let reference = reference_of(scene, camera, size);
    let resources = FrameResources::new(c, &pipeline, size).unwrap();
    let slots = slots_from_reference(scene, &gpu, &reference);
    let buffer = |name: &str| resources.buffer(pipeline.resource(name).unwrap());
    if !slots.is_empty() {
        c.queue
            .write_buffer(buffer("ssbvb"), 0, bytemuck::cast_slice(&slots));
    }
    c.queue.write_buffer(
        buffer("billboard_draw"),
        0,
        bytemuck::cast_slice(&[6u32, slots.len() as u32, 0, 0]),
    );
    let mut nodes: Vec<(usize, Box<dyn PassNode>)> = Vec::new();
    let find = |name: &str| pipeline.passes.iter().position(|p| p.name == name).unwrap();
    if triangles {
        let i = find("triangles");
        nodes.push((
            i,
            Box::new(
                <Triangles as PassImpl>::new(
                    &PassInit {
                        ctx: c,
                        scene: &gpu,
                        pipeline: &pipeline,
                        pass: &pipeline.passes[i],
                    },
                    &ssbvb_graph::TrianglesKind,
                )
                .unwrap(),
            ),
        ));
    }
    if let Some(o) = billboards {
        let i = find("billboards");
        let node = c
            .validated("billboards pipeline", |_| {
                Billboards::with_options(
                    &PassInit {
                        ctx: c,
                        scene: &gpu,
                        pipeline: &pipeline,
                        pass: &pipeline.passes[i],
                    },
                    o,
                )
            })
            .unwrap()
            .unwrap();
        nodes.push((i, Box::new(node)));
    }
    let mut encoder = c.device.create_command_encoder(&Default::default());
    let gbuffer_slots: [&'static str; 5] = [
        "gbuffer_albedo",
        "gbuffer_normal",
        "gbuffer_position",
        "gbuffer_geometric_normal",
        "depth_stencil",
    ];
    for (k, (i, node)) in nodes.iter_mut().enumerate() {
        let firsts: &[&'static str] = if k == 0 { &gbuffer_slots } else { &[] };
        let mut rec = Recorder {
            gpu: c,
            scene: &gpu,
            resources: &resources,
            pass: &pipeline.passes[*i],
            screen: size,
            timestamps: None,
            first_writes: firsts,
            counting: false,
        };
        c.validated("record", |_| node.record(&mut encoder, &mut rec))
            .unwrap()
            .unwrap();
    }
    c.validated("submit", |_| c.queue.submit([encoder.finish()]))
        .unwrap();
    c.wait_idle().unwrap();
    let errs = c.take_uncaptured_errors();
    assert!(errs.is_empty(), "wgpu errors: {errs:#?}");
    let g = GBuffer::read(&pipeline, &resources);
    g.assert_finite();
    (g, reference)
}

/// Accuracy of a G-buffer against the reference (voxel pixels only), from
/// `ssbvb_voxel::accuracy::compare` plus what only a G-buffer shows.
#[derive(Debug, Clone, Copy)]
#[allow(dead_code)] // Every field is printed in the logs; tests assert on some.
pub(crate) struct Accuracy {
    /// |GPU ∩ reference| / |GPU ∪ reference| of covered pixels.
    pub iou: f64,
    /// Pixels covered by the GPU only, by the reference only, by both.
    pub gpu_only: usize,
    pub ref_only: usize,
    pub both: usize,
    /// Among pixels both cover, the fraction whose G-buffer position (nudged 1e-3 cell along
    /// the ray) lies in the reference's voxel. Exact for RayBox; for Flat the position is on
    /// the quad, so this is a lower bound of the same-voxel rate.
    pub same_voxel: f64,
    /// |t - reference t| in cells (t = |position.xyz|): median and 95th percentile.
    pub depth_median: f64,
    pub depth_p95: f64,
    /// |linear depth (position.w) - reference view depth| in cells, median: what a flat
    /// quad at the voxel centre's depth gets wrong along the view axis (0.5 face-on).
    pub view_depth_median: f64,
    /// Angle between the G-buffer's geometric normal and the reference face normal, degrees.
    pub face_normal_median: f64,
    pub face_normal_p95: f64,
    /// Angle between the G-buffer's shading normal and the stored normal of the reference
    /// voxel (world space), degrees: ~0 when the billboard that won the pixel is the
    /// reference's voxel, in both modes.
    pub stored_normal_median: f64,
    /// Largest |position.xyz - reference hit position| in cells.
    pub position_max: f64,
}

/// Compares a billboards-only G-buffer with the reference.
pub(crate) fn measure(g: &GBuffer, r: &ReferenceImage, scene: &Scene, camera: &Camera) -> Accuracy {
    // Instances in the reference's order: transform, LOD, world size of a cell.
    let mut insts = Vec::new();
    for o in &scene.objects {
        let LodPolicy::Fixed(l) = o.lod else {
            panic!("fixed LODs only")
        };
        let lod = &o.asset.lods[l.min(o.asset.lods.len() as u32 - 1) as usize];
        for xf in &o.instances {
            let cell = xf.matrix3.determinant().abs().cbrt() * cell_world(lod.level);
            insts.push((*xf, lod, cell));
        }
    }
    let cells: Vec<f64> = insts.iter().map(|i| i.2).collect();
    let min_cell = cells.iter().copied().fold(f64::INFINITY, f64::min);
    let rays = camera.pixel_rays(g.width, g.height);
    let hits: Vec<Option<GpuHit>> = (0..g.albedo.len())
        .map(|i| {
            if !g.covered(i) {
                return None;
            }
            let p = g.position[i];
            let rel = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            let (_, dir) = rays.ray(i as u32 % g.width, i as u32 / g.width);
            let probe = camera.position + rel + dir * (1e-3 * min_cell);
            let found = insts.iter().enumerate().find_map(|(k, (xf, lod, _))| {
                let o = xf.inverse().transform_point3(probe);
                let n = (1u64 << lod.level) as f64;
                let c = ((o + 1.0) * 0.5 * n).floor();
                if c.min_element() < 0.0 || c.max_element() >= n {
                    return None;
                }
                let cell = [c.x as u32, c.y as u32, c.z as u32];
                lod.lookup.get(cell).map(|_| (k as u32, cell))
            });
            let (instance, cell) = found.unwrap_or((u32::MAX, [u32::MAX; 3]));
            Some(GpuHit {
                instance,
                cell,
                t: rel.length(),
                normal: g.geometric[i],
            })
        })
        .collect();
    let rep = accuracy::compare(r, &hits, &cells).unwrap();
    let (mut stored, mut view_depth, mut pos_max) = (vec![], vec![], 0.0f64);
    for (i, h) in r.hits.iter().enumerate() {
        let Some(h) = h else { continue };
        if !g.covered(i) {
            continue;
        }
        let (xf, lod, cell) = insts[h.instance as usize];
        let p = g.position[i];
        let rel = h.position - camera.position;
        let err = (DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) - rel).length() / cell;
        pos_max = pos_max.max(err);
        view_depth.push((p[3] as f64 - h.view_depth).abs() / cell);
        let v = lod.point_cloud.voxels[h.voxel as usize];
        let nm: DMat3 = xf.matrix3.inverse().transpose();
        let sn = (nm * DVec3::from(v.normal().map(|x| x as f64))).as_vec3();
        stored.push(accuracy::angle_deg(
            [g.normal[i][0], g.normal[i][1], g.normal[i][2]],
            sn.into(),
        ));
    }
    Accuracy {
        iou: rep.coverage_iou,
        gpu_only: rep.covered_gpu - rep.covered_both,
        ref_only: rep.covered_reference - rep.covered_both,
        both: rep.covered_both,
        same_voxel: rep.same_voxel_rate,
        depth_median: rep.depth_error_voxels.median,
        depth_p95: rep.depth_error_voxels.p95,
        view_depth_median: ErrorStats::of(view_depth).median,
        face_normal_median: rep.normal_error_deg.median,
        face_normal_p95: rep.normal_error_deg.p95,
        stored_normal_median: ErrorStats::of(stored).median,
        position_max: pos_max,
    }
}

pub(crate) const SIZE: (u32, u32) = (160, 120);
/// Level 6 (64 cells over 2 world units): at distance ~3 with a 45° field of view and 120
/// rows a cell spans ~1.5 pixels.
pub(crate) const LEVEL: u32 = 6;
pub(crate) const BUNNY: &str = "bunny.obj";
pub(crate) const VOX: &str = "chr_knight.vox";

pub(crate) fn cameras() -> Vec<(&'static str, Camera)> {
    vec![
        ("front", Camera::new(DVec3::new(0.3, 0.4, 2.9), DVec3::ZERO)),
        (
            "side",
            Camera::new(DVec3::new(2.6, 1.1, -0.9), DVec3::new(0.0, 0.1, 0.0)),
        ),
        ("top", Camera::new(DVec3::new(-0.8, 2.7, 1.1), DVec3::ZERO)),
        // On the z axis: pixel rays run along cell boundary planes.
        ("axis", Camera::new(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO)),
    ]
}

/// Flat quads lie at the voxel centre's view depth: face-on that is half a cell behind the
/// entered face along the view axis, and `0.5 / cos(angle to the axis)` cells along the
/// pixel's ray (up to 0.6 in the corners of a 45° 4:3 view). Medians must stay within that.
pub(crate) fn assert_flat_depth(a: &Accuracy, what: &str) {
    assert!(a.view_depth_median <= 0.5 + 1e-3, "{what}: {a:?}");
    assert!(a.depth_median <= 0.6, "{what}: {a:?}");
}

pub(crate) fn options(mode: BillboardMode) -> BillboardOptions {
    BillboardOptions {
        mode,
        size_scale: 1.0,
        footprint: Footprint::Box,
        cull_cos: DEFAULT_CULL_COS,
    }
}

pub(crate) fn cell_world(level: u32) -> f64 {
    2.0 / (1u64 << level) as f64
}
