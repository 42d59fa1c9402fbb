//! Pipelines that include others: the merged description, replacement by name, errors
//! located in the file they are in, and reloads that follow the included files.

use std::collections::HashMap;

use ssbvb_graph::include::{include_path, includes_of};
use ssbvb_graph::{PipelineErrors, ResolvedPipeline, resolve_str, resolve_str_with};

/// Shared declarations: the G-buffer, the triangles and the deferred shading.
const SHARED: &str = include_str!("include/deferred.ron");

/// The ESVO frame's own part.
const ESVO_OWN: &str = include_str!("include/esvo_own.ron");

/// The ESVO frame of `p/esvo.ron` with its composite replaced by the compute one.
const COMPOSITE_IN_COMPUTE: &str = include_str!("include/composite_in_compute.ron");

/// The bundled ESVO frame, written whole.
const ESVO_WHOLE: &str = include_str!("../../../assets/pipelines/esvo.ron");

fn files(pairs: &[(&str, &str)]) -> HashMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn resolve_in(
    map: &HashMap<String, String>,
    file: &str,
) -> Result<ResolvedPipeline, PipelineErrors> {
    let read = |p: &str| {
        map.get(p)
            .cloned()
            .ok_or_else(|| "no such file".to_string())
    };
    resolve_str_with(&map[file], file, &read)
}

fn kind_of(p: &ResolvedPipeline, pass: &str) -> ssbvb_graph::PassKind {
    let found = p.desc.passes.iter().find(|s| s.name == pass);
    found.unwrap().kind.clone()
}

fn names(p: &ResolvedPipeline) -> Vec<&str> {
    p.passes.iter().map(|s| s.name.as_str()).collect()
}

#[test]
fn an_included_file_declares_what_the_whole_file_declares() {
    let map = files(&[("p/esvo.ron", ESVO_OWN), ("p/shared/deferred.ron", SHARED)]);
    let split = resolve_in(&map, "p/esvo.ron").unwrap();
    let whole = resolve_str(ESVO_WHOLE, "esvo.ron").unwrap();
    assert_eq!(names(&split), names(&whole));
    assert_eq!(split.sources, ["p/esvo.ron", "p/shared/deferred.ron"]);
    assert!(
        split.desc.include.is_empty(),
        "the merged description includes nothing"
    );
    // The same resources (order aside: the included ones follow the file's own).
    let mut a: Vec<_> = split.desc.resources.0.clone();
    let mut b: Vec<_> = whole.desc.resources.0.clone();
    a.sort_by(|x, y| x.0.cmp(&y.0));
    b.sort_by(|x, y| x.0.cmp(&y.0));
    assert_eq!(a, b);
    assert_eq!(split.physical.len(), whole.physical.len());
}

#[test]
fn a_pass_of_the_same_name_replaces_the_included_one_in_place() {
    let variant = COMPOSITE_IN_COMPUTE;
    let map = files(&[
        ("p/esvo.ron", ESVO_OWN),
        ("p/shared/deferred.ron", SHARED),
        ("p/variant.ron", variant),
    ]);
    let p = resolve_in(&map, "p/variant.ron").unwrap();
    let base = resolve_in(&map, "p/esvo.ron").unwrap();
    assert_eq!(names(&p), names(&base), "one pass replaced, none added");
    assert_eq!(
        kind_of(&p, "composite"),
        ssbvb_graph::PassKind::CompositeCompute
    );
    assert_eq!(
        p.desc.output, "color",
        "the output comes from the included file"
    );
    assert_eq!(p.sources.len(), 3);
    let color = p.desc.resources.0.iter().filter(|r| r.0 == "color").count();
    assert_eq!(color, 1, "the resource replaced, not declared twice");
}

#[test]
fn an_error_in_an_included_file_names_that_file_and_line() {
    let broken = SHARED.replace(
        r#"reads: ["gbuffer_normal", "depth_stencil"],"#,
        r#"reads: ["gbuffer_normall", "depth_stencil"],"#,
    );
    let map = files(&[("p/esvo.ron", ESVO_OWN), ("p/shared/deferred.ron", &broken)]);
    let e = resolve_in(&map, "p/esvo.ron").unwrap_err().to_string();
    // Line 21 of the shared file holds the smoothing pass's reads.
    assert!(e.contains("p/shared/deferred.ron:21:"), "{e}");
    assert!(e.contains("gbuffer_normall"), "{e}");
    let own_lines = e
        .lines()
        .skip(1)
        .filter(|l| l.trim_start().starts_with("p/esvo.ron"));
    assert_eq!(own_lines.count(), 0, "{e}");
    // An error in the including file names it.
    let own = ESVO_OWN.replace(r#"after: ["triangles"]"#, r#"after: ["triangle"]"#);
    let map = files(&[("p/esvo.ron", &own), ("p/shared/deferred.ron", SHARED)]);
    let e = resolve_in(&map, "p/esvo.ron").unwrap_err().to_string();
    assert!(e.contains("p/esvo.ron:8:"), "{e}");
}

#[test]
fn a_missing_or_circular_include_is_an_error_at_its_entry() {
    let map = files(&[("p/esvo.ron", ESVO_OWN)]);
    let e = resolve_in(&map, "p/esvo.ron").unwrap_err().to_string();
    assert!(
        e.contains("p/esvo.ron:2:") && e.contains("cannot read `p/shared/deferred.ron`"),
        "{e}"
    );
    let looped = SHARED.replace("Pipeline(", r#"Pipeline(include: ["../esvo.ron"],"#);
    let map = files(&[("p/esvo.ron", ESVO_OWN), ("p/shared/deferred.ron", &looped)]);
    let e = resolve_in(&map, "p/esvo.ron").unwrap_err().to_string();
    assert!(e.contains("includes itself"), "{e}");
    // A syntax error in the included file is its own.
    let map = files(&[
        ("p/esvo.ron", ESVO_OWN),
        ("p/shared/deferred.ron", "Pipeline("),
    ]);
    let e = resolve_in(&map, "p/esvo.ron").unwrap_err().to_string();
    assert!(e.contains("p/shared/deferred.ron:1:"), "{e}");
}

#[test]
fn shared_declarations_alone_are_no_pipeline() {
    let e = resolve_str(SHARED, "shared.ron").unwrap_err().to_string();
    assert!(e.contains("no `output:`"), "{e}");
}

#[test]
fn include_paths_are_relative_to_the_including_file() {
    assert_eq!(
        include_path("a/b/p.ron", "shared/s.ron"),
        "a/b/shared/s.ron"
    );
    assert_eq!(include_path("p.ron", "s.ron"), "s.ron");
    assert_eq!(
        include_path("http://h/assets/pipelines/p.ron", "shared/s.ron"),
        "http://h/assets/pipelines/shared/s.ron"
    );
    assert_eq!(include_path("a/p.ron", "/abs/s.ron"), "/abs/s.ron");
    assert_eq!(include_path("a/shared/s.ron", "../p.ron"), "a/p.ron");
    assert_eq!(include_path("a/./p.ron", "./s.ron"), "a/s.ron");
    assert_eq!(include_path("p.ron", "../s.ron"), "../s.ron");
    assert_eq!(includes_of(ESVO_OWN), ["shared/deferred.ron"]);
    assert!(includes_of(ESVO_WHOLE).is_empty());
    assert!(includes_of("not ron (").is_empty());
}

#[test]
fn the_watcher_reloads_when_an_included_file_changes() {
    use ssbvb_graph::{PipelineWatcher, ReloadOutcome};
    let dir = std::env::temp_dir().join(format!("ssbvb-include-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("shared")).unwrap();
    let path = dir.join("esvo.ron");
    std::fs::write(&path, ESVO_OWN).unwrap();
    std::fs::write(dir.join("shared/deferred.ron"), SHARED).unwrap();
    let mut w = PipelineWatcher::new(&path).unwrap();
    assert!(matches!(w.poll(), ReloadOutcome::Unchanged));
    // The smoothing pruned by an edit of the included file only.
    reloads_unsmoothed(&mut w, &dir.join("shared/deferred.ron"), SHARED);
    std::fs::remove_dir_all(&dir).ok();
}

/// Writes `text` with the composite reading the unsmoothed normal to `file`, and checks
/// that `w` reloads with the smoothing pruned.
fn reloads_unsmoothed(w: &mut ssbvb_graph::PipelineWatcher, file: &std::path::Path, text: &str) {
    let edited = text.replace(
        r#""normal": "smoothed_normal""#,
        r#""normal": "gbuffer_normal""#,
    );
    assert_ne!(edited, text);
    std::fs::write(file, edited).unwrap();
    assert!(matches!(w.poll(), ssbvb_graph::ReloadOutcome::Reloaded));
    assert_eq!(w.current().pruned_passes, ["smooth"]);
}

#[test]
fn the_old_paths_of_renamed_bundled_files_still_load() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/pipelines");
    for (old, new) in ssbvb_graph::RENAMED_FILES {
        let old_path = std::path::Path::new(dir).join(old);
        assert!(!old_path.exists(), "{old} is back");
        let p = ssbvb_graph::resolve_file(&old_path).unwrap();
        assert!(p.file.ends_with(new), "{}", p.file);
    }
    // A missing file of another name is still an error naming it.
    let e = ssbvb_graph::resolve_file(&std::path::Path::new(dir).join("nope.ron")).unwrap_err();
    assert!(e.to_string().contains("nope.ron"), "{e}");
}

#[test]
fn a_duplicate_inside_an_included_file_is_still_reported() {
    let doubled = SHARED.replace(
        r#"    "color":            Texture(format: Rgba8UnormSrgb, size: Screen),"#,
        r#"    "color":            Texture(format: Rgba8UnormSrgb, size: Screen),
    "color":            Texture(format: Rgba8UnormSrgb, size: Screen),"#,
    );
    assert_ne!(doubled, SHARED);
    let map = files(&[
        ("p/esvo.ron", ESVO_OWN),
        ("p/shared/deferred.ron", &doubled),
    ]);
    let e = resolve_in(&map, "p/esvo.ron").unwrap_err().to_string();
    assert!(
        e.contains("p/shared/deferred.ron:") && e.contains("color"),
        "{e}"
    );
}

#[test]
fn a_file_included_by_two_ways_is_merged_once_and_an_override_stays() {
    // The variant includes the ESVO frame (which includes the shared file), replaces the
    // composite, then includes the shared file again: the replacement must stay.
    let variant = r#"Pipeline(
  include: ["esvo_compute_composite.ron", "shared/deferred.ron"],
)"#;
    let middle = COMPOSITE_IN_COMPUTE;
    let map = files(&[
        ("p/esvo.ron", ESVO_OWN),
        ("p/shared/deferred.ron", SHARED),
        ("p/esvo_compute_composite.ron", middle),
        ("p/variant.ron", variant),
    ]);
    let p = resolve_in(&map, "p/variant.ron").unwrap();
    assert_eq!(
        kind_of(&p, "composite"),
        ssbvb_graph::PassKind::CompositeCompute
    );
    assert_eq!(p.sources.len(), 4, "{:?}", p.sources);
}

#[test]
fn includes_nest_to_a_bound_and_read_only_regular_files() {
    // A chain of files each including the next: past the bound it is an error.
    let mut pairs: Vec<(String, String)> = Vec::new();
    for i in 0..40 {
        pairs.push((
            format!("c/{i}.ron"),
            format!(r#"Pipeline(include: ["{}.ron"])"#, i + 1),
        ));
    }
    pairs.push(("c/40.ron".into(), SHARED.into()));
    let map: HashMap<String, String> = pairs.into_iter().collect();
    let e = resolve_in(&map, "c/0.ron").unwrap_err().to_string();
    assert!(e.contains("nest deeper than"), "{e}");
    // The file system reader refuses what is not a regular file.
    assert!(ssbvb_graph::include::read_file("/dev/null").is_err());
    assert!(ssbvb_graph::include::read_file(env!("CARGO_MANIFEST_DIR")).is_err());
}

#[test]
fn the_watcher_of_a_renamed_files_old_path_watches_the_new_file() {
    use ssbvb_graph::{PipelineWatcher, ReloadOutcome};
    let dir = std::env::temp_dir().join(format!("ssbvb-renamed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("ssbvb_unique.ron"), ESVO_WHOLE).unwrap();
    let mut w = PipelineWatcher::new(dir.join("ssbvb.ron")).unwrap();
    assert!(matches!(w.poll(), ReloadOutcome::Unchanged));
    reloads_unsmoothed(&mut w, &dir.join("ssbvb_unique.ron"), ESVO_WHOLE);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn after_a_failed_reload_a_newly_included_file_is_watched() {
    use ssbvb_graph::{PipelineWatcher, ReloadOutcome};
    let dir = std::env::temp_dir().join(format!("ssbvb-new-include-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("shared")).unwrap();
    std::fs::write(dir.join("shared/deferred.ron"), SHARED).unwrap();
    std::fs::write(dir.join("p.ron"), ESVO_WHOLE).unwrap();
    let mut w = PipelineWatcher::new(dir.join("p.ron")).unwrap();
    // The file now includes a broken file: the reload fails.
    std::fs::write(dir.join("shared/broken.ron"), "Pipeline(").unwrap();
    std::fs::write(
        dir.join("p.ron"),
        ESVO_OWN.replace("shared/deferred.ron", "shared/broken.ron"),
    )
    .unwrap();
    assert!(matches!(w.poll(), ReloadOutcome::Failed(_)));
    // Fixing the included file alone reloads.
    std::fs::write(dir.join("shared/broken.ron"), SHARED).unwrap();
    assert!(matches!(w.poll(), ReloadOutcome::Reloaded));
    assert_eq!(w.current().sources.len(), 2);
    std::fs::remove_dir_all(&dir).ok();
}
