//! `ssbvb voxelize MODEL --level N --gpu [--gpu-method exact|raster] --json`: the CPU
//! path's keys plus `differs_from_cpu` and `gpu`.

use std::path::Path;

use super::{ssbvb, stdout_json, succeeded};

#[test]
fn voxelize_gpu_reports_the_cpu_keys_and_the_difference() {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models");
    let dir = tempfile::tempdir().unwrap();
    let out = succeeded(
        ssbvb()
            .env("SSBVB_CACHE_DIR", dir.path().join("cache"))
            .arg("voxelize")
            .arg(models.join("bunny.obj"))
            .args(["--level", "6", "--json"]),
    );
    let cpu = stdout_json(&out);
    let asset = dir.path().join("bunny_gpu.ssbvb");
    let out = succeeded(
        ssbvb()
            .arg("voxelize")
            .arg(models.join("bunny.obj"))
            .args(["--level", "6", "--gpu", "--json", "-o"])
            .arg(&asset),
    );
    let gpu = stdout_json(&out);
    for key in cpu.as_object().unwrap().keys() {
        assert!(gpu.get(key).is_some(), "--gpu lacks `{key}`: {gpu}");
    }
    assert_eq!(gpu["cache"]["status"], "disabled");
    assert!(asset.is_file(), "-o wrote the asset");
    let diff = gpu["differs_from_cpu"].as_array().unwrap();
    assert_eq!(diff.len(), 7, "levels 6 down to 0: {diff:?}");
    let finest = &diff[0];
    assert_eq!(finest["level"], 6);
    let cpu_voxels = finest["cpu_voxels"].as_u64().unwrap();
    // The CPU path's own count at level 6.
    assert_eq!(cpu["levels"][6]["voxels"].as_u64().unwrap(), cpu_voxels);
    assert_eq!(gpu["levels"][6]["voxels"], finest["gpu_voxels"]);
    // The default on an adapter with f64 shaders (lavapipe has them) is the exact path:
    // the CPU's very voxels at every level.
    assert_eq!(gpu["gpu"]["method"], "Exact", "{gpu}");
    for d in diff {
        let counts = (d["extra"].as_u64(), d["missing"].as_u64());
        assert_eq!(counts, (Some(0), Some(0)), "{d}");
    }
    assert!(gpu["gpu"]["fragments"].as_u64().unwrap() >= cpu_voxels);
    assert!(gpu["gpu"]["cpu_seconds"].as_f64().unwrap() > 0.0);
    // The raster path: a near superset (measured: 464 extra, 0 missing of 14 027).
    let out = succeeded(ssbvb().arg("voxelize").arg(models.join("bunny.obj")).args([
        "--level",
        "6",
        "--gpu",
        "--gpu-method",
        "raster",
        "--json",
    ]));
    let raster = stdout_json(&out);
    assert_eq!(raster["gpu"]["method"], "Raster");
    let finest = &raster["differs_from_cpu"][0];
    let extra = finest["extra"].as_u64().unwrap();
    assert!(extra > 0 && extra * 10 <= cpu_voxels, "{finest}");
    assert!(
        finest["missing"].as_u64().unwrap() * 1000 <= cpu_voxels,
        "{finest}"
    );
    // A voxel model is refused with the reason.
    let out = ssbvb()
        .arg("voxelize")
        .arg(models.join("chr_knight.vox"))
        .args(["--level", "5", "--gpu"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("chr_knight.vox") && err.contains("--gpu voxelizes meshes"),
        "{err}"
    );
}
