//! The partitioned build (`PmOptions::block_vertices`, docs/partitioned.md): small blocks make
//! many borders on small meshes; the hierarchy must replay exactly, keep the topology, not
//! depend on the thread count, and filter like the one-process hierarchy.

use glam::DVec3;
use meshpyr::PyrContent;
use meshpyr::format::container::{Container, REQUIRED, Section, write_container};
use meshpyr::format::varint::put_uvarint;
use meshpyr::format::{self};
use meshpyr::io::read_mesh;
use meshpyr::mesh::SlotIndex;
use meshpyr::mesh::{Mesh, PolygonMesh};
use meshpyr::pm::blocks::{BlockFileError, SharedRunner, Task, TaskOutput, TaskRunner, run_task};
use meshpyr::pm::{FirstPieces, MeshRecords, PmOptions, ProgressiveMesh};
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{DetailPyramid, DetailSource, Filter, LevelGains, Pyramid, PyramidOptions};
use meshpyr::relax::{MeanCurvatureStep, Relaxation, SecondDifference};
use proptest::prelude::*;
use std::sync::Arc;

mod common;

fn blocks(n: usize) -> PmOptions {
    PmOptions {
        block_vertices: Some(n),
        ..PmOptions::default()
    }
}

/// The parts a `.pyr` file stores, rebuilt through the validating constructor: it replays
/// every split on the base mesh and compares the result with the finest faces.
fn replayed(pm: &ProgressiveMesh) -> ProgressiveMesh {
    ProgressiveMesh::from_parts(pm.to_parts()).expect("the splits replay exactly to the input")
}

/// Walks the hierarchy down to the base and up again: every collapse is the inverse of its
/// split, and the finest level comes back record for record.
fn assert_walks_exactly(name: &str, pm: &ProgressiveMesh) {
    let mut cursor = pm.cursor();
    let finest = MeshRecords::of(cursor.mesh());
    let mut steps = 0;
    while cursor.collapse() {
        steps += 1;
        if steps % 97 == 0 {
            cursor.mesh().validate().unwrap();
        }
    }
    assert_eq!(cursor.level(), pm.n_base_vertices(), "{name}");
    cursor.mesh().validate().unwrap();
    while cursor.split() {}
    assert_eq!(MeshRecords::of(cursor.mesh()), finest, "{name}");
}

fn load(name: &str) -> PolygonMesh {
    read_mesh(common::data(name)).unwrap()
}

#[test]
fn a_hierarchy_built_in_small_blocks_replays_exactly_and_keeps_the_topology() {
    // Closed, open with holes, dirty with many components and repaired spots.
    for (name, block) in [
        ("bunny.ply", 500),
        ("elephant_holes.ply", 300),
        ("spider_assimp.ply", 64),
        ("tripod.ply", 200),
    ] {
        let poly = load(name);
        let (pm, _) = ProgressiveMesh::from_polygons(&poly, &blocks(block), &NoProgress).unwrap();
        let (whole, _) =
            ProgressiveMesh::from_polygons(&poly, &PmOptions::default(), &NoProgress).unwrap();
        assert_eq!(pm.n_vertices(), whole.n_vertices(), "{name}");
        let in_input = |pm: &ProgressiveMesh| -> Vec<[u32; 3]> {
            let faces = pm.finest_faces().iter();
            faces
                .map(|t| t.map(|v| pm.pm_to_mesh()[v as usize]))
                .collect()
        };
        assert!(in_input(&pm) == in_input(&whole), "{name}: finest faces");
        let again = replayed(&pm);
        assert_eq!(again.n_base_faces(), pm.n_base_faces(), "{name}");
        assert_walks_exactly(name, &pm);
        let (a, b) = (pm.base_mesh().topology(), whole.base_mesh().topology());
        assert_eq!(a.components, b.components, "{name}: components");
        assert_eq!(a.genus, b.genus, "{name}: genus");
        assert_eq!(a.boundary_loops, b.boundary_loops, "{name}: holes");
        // Blocks never relax the rules; the root does, as the one-process build at its end,
        // so the base is as coarse as the whole mesh's up to a few vertices per component.
        let slack = 8 * b.components + 16;
        assert!(
            pm.n_base_vertices() <= whole.n_base_vertices() + slack,
            "{name}: base {} vertices, one process {}",
            pm.n_base_vertices(),
            whole.n_base_vertices()
        );
    }
}

#[test]
fn a_partitioned_hierarchy_does_not_depend_on_the_thread_count() {
    let poly = load("elephant_holes.ply");
    let build = || {
        let options = PyramidOptions {
            pm: blocks(400),
            ..PyramidOptions::default()
        };
        let p = Pyramid::build_with(poly.clone(), &options, &NoProgress).unwrap();
        p.to_pyr_bytes().unwrap().0
    };
    let one = common::on_threads(1, build);
    for threads in [2, 4] {
        assert!(
            common::on_threads(threads, build) == one,
            "{threads} threads wrote other bytes"
        );
    }
}

/// A scratch directory of this test process under the system's temporary directory.
fn scratch(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("meshpyr-test-{}-{name}", std::process::id()))
}

fn pyr_bytes(poly: &PolygonMesh, pm: PmOptions) -> Vec<u8> {
    let options = PyramidOptions {
        pm,
        ..PyramidOptions::default()
    };
    let p = Pyramid::build_with(poly.clone(), &options, &NoProgress).unwrap();
    p.to_pyr_bytes().unwrap().0
}

#[test]
fn passes_run_through_task_files_write_the_same_pyr_bytes_as_passes_in_memory() {
    for (name, block, threads) in [
        ("elephant_holes.ply", 400, 1),
        ("elephant_holes.ply", 400, 3),
        ("bunny.ply", 500, 2),
        ("spider_assimp.ply", 64, 2),
        ("tripod.ply", 1000, 1),
    ] {
        let poly = load(name);
        let dir = scratch(&format!("files-{block}-{threads}"));
        let in_memory = common::on_threads(threads, || pyr_bytes(&poly, blocks(block)));
        let through_files = PmOptions {
            block_scratch: Some(dir.clone()),
            ..blocks(block)
        };
        let files = common::on_threads(threads, || pyr_bytes(&poly, through_files));
        assert!(
            files == in_memory,
            "{name}, blocks of {block}, {threads} threads"
        );
        let left = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(left, 0, "{name}: the task files are removed");
        std::fs::remove_dir(&dir).unwrap();
    }
}

/// The hierarchy of `poly`, read from `path`, built in blocks of `block` through files, and
/// how its first pieces were made.
fn built_from_file(poly: &PolygonMesh, path: &std::path::Path, block: usize) -> (Vec<u8>, String) {
    let options = PmOptions {
        block_scratch: Some(path.with_extension("blocks")),
        block_input: Some(path.to_path_buf()),
        ..blocks(block)
    };
    let (pm, _) = ProgressiveMesh::from_polygons(poly, &options, &NoProgress).unwrap();
    let first = pm
        .first_pieces()
        .expect("said on the file path")
        .to_string();
    let bytes = pyr_bytes(poly, options);
    (bytes, first)
}

#[test]
fn a_ply_split_into_cells_and_an_obj_of_the_same_mesh_write_the_pyr_bytes_of_the_blocks_in_memory()
{
    let dir = tempfile::tempdir().unwrap();
    for (name, block) in [("elephant_holes.ply", 400), ("spider_assimp.ply", 64)] {
        let poly = load(name);
        let in_memory = pyr_bytes(&poly, blocks(block));
        let ply = dir.path().join("scan.ply");
        let obj = dir.path().join("scan.obj");
        meshpyr::io::write_mesh(&ply, &poly).unwrap();
        meshpyr::io::write_mesh(&obj, &poly).unwrap();
        let (from_cells, first) = built_from_file(&poly, &ply, block);
        assert!(
            first.contains("split from the file into cells"),
            "{name}: {first}"
        );
        assert!(from_cells == in_memory, "{name}: the cells' first pieces");
        let (from_whole, first) = built_from_file(&poly, &obj, block);
        assert!(first.contains("PLY files only"), "{name}: {first}");
        assert!(from_whole == in_memory, "{name}: the OBJ's whole mesh");
    }
}

#[test]
fn a_scan_whose_repair_the_cells_refuse_is_built_from_the_whole_mesh_with_the_same_bytes() {
    // A Möbius band: the builder cuts the edge its walk over the whole component meets first,
    // which no cell can decide alone.
    let poly = common::mobius_band(400);
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("mobius.ply");
    meshpyr::io::write_mesh(&ply, &poly).unwrap();
    let (bytes, first) = built_from_file(&poly, &ply, 64);
    assert!(
        first.contains("whole mesh") && first.contains("cannot be oriented"),
        "{first}"
    );
    assert!(bytes == pyr_bytes(&poly, blocks(64)));
}

/// Runs each round's tasks last first, one at a time, each twice (a retried task), and checks
/// that the second run wrote the same bytes as the first.
struct ReversedTwice;

impl TaskRunner for ReversedTwice {
    fn run_round(&self, tasks: Vec<Task>) -> Result<Vec<TaskOutput>, BlockFileError> {
        let mut outputs = Vec::with_capacity(tasks.len());
        for task in tasks.iter().rev() {
            let first = run_task(task)?;
            let written = written_files(task);
            let bytes: Vec<Vec<u8>> = written.iter().map(|f| std::fs::read(f).unwrap()).collect();
            assert_eq!(run_task(task)?, first, "{task:?}");
            for (f, b) in written.iter().zip(bytes) {
                assert!(
                    std::fs::read(f).unwrap() == b,
                    "{} changed when run again",
                    f.display()
                );
            }
            outputs.push(first);
        }
        outputs.reverse();
        Ok(outputs)
    }
}

fn written_files(task: &Task) -> Vec<std::path::PathBuf> {
    match task {
        Task::Split {
            across_out,
            routed_out,
            ..
        } => vec![across_out.clone(), routed_out.clone()],
        Task::Concat { out, .. } => vec![out.clone()],
        Task::Gather {
            input_out,
            held_out,
            ..
        } => vec![input_out.clone(), held_out.clone()],
        Task::Candidates { costs_out, .. } => vec![costs_out.clone()],
        Task::CostHistogram { .. } => vec![],
        Task::Collapse { result_out, .. } | Task::Finish { result_out, .. } => {
            vec![result_out.clone()]
        }
        Task::Assemble { sequence_out, .. } => vec![sequence_out.clone()],
        Task::CellPatches { patches_out, .. } => vec![patches_out.clone()],
        Task::CellFans { fans_out, .. } => vec![fans_out.clone()],
        Task::CellPiece { piece_out, .. } => vec![piece_out.clone()],
    }
}

#[test]
fn any_order_of_a_rounds_tasks_and_retried_tasks_give_the_same_pyr_bytes() {
    let poly = load("elephant_holes.ply");
    let in_memory = pyr_bytes(&poly, blocks(300));
    let options = PmOptions {
        block_scratch: Some(scratch("reversed")),
        block_runner: Some(SharedRunner(Arc::new(ReversedTwice))),
        ..blocks(300)
    };
    assert!(pyr_bytes(&poly, options.clone()) == in_memory);
    std::fs::remove_dir(scratch("reversed")).unwrap();
    // The cell tasks' rounds too, from the file split into cells.
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("scan.ply");
    meshpyr::io::write_mesh(&ply, &poly).unwrap();
    let from_cells = PmOptions {
        block_scratch: Some(dir.path().join("blocks")),
        block_input: Some(ply),
        ..options
    };
    let (pm, _) = ProgressiveMesh::from_polygons(&poly, &from_cells, &NoProgress).unwrap();
    assert_eq!(pm.first_pieces(), Some(&FirstPieces::Cells));
    assert!(pyr_bytes(&poly, from_cells) == in_memory);
}

#[test]
fn a_scratch_directory_that_cannot_be_made_is_an_error_naming_it() {
    let file = scratch("not-a-directory");
    std::fs::write(&file, b"x").unwrap();
    let options = PmOptions {
        block_scratch: Some(file.join("under")),
        ..blocks(400)
    };
    let poly = load("tripod.ply");
    let err = ProgressiveMesh::from_polygons(&poly, &options, &NoProgress).unwrap_err();
    std::fs::remove_file(&file).unwrap();
    assert!(err.to_string().contains("not-a-directory"), "{err}");
}

#[test]
fn a_partitioned_hierarchy_carries_the_pins_of_its_passes_in_memory_and_through_files() {
    let poly = load("elephant_holes.ply");
    let (whole, _) =
        ProgressiveMesh::from_polygons(&poly, &PmOptions::default(), &NoProgress).unwrap();
    assert!(whole.pins().is_none(), "one process pins nothing");
    let (pm, _) = ProgressiveMesh::from_polygons(&poly, &blocks(400), &NoProgress).unwrap();
    let pins = pm.pins().expect("blocks pin their borders");
    let survivor = |k: usize| pm.splits()[k].survivor;
    pins.check(pm.n_base_vertices(), pm.splits().len(), survivor)
        .unwrap();
    let passes: Vec<_> = pins.passes().collect();
    assert!(passes.len() >= 3, "{} passes", passes.len());
    // Split order: the last block (nothing pinned) comes first, then the passes, each with
    // a border.
    assert!(passes[0].1.is_empty());
    assert!(passes[1..].iter().all(|(_, pinned)| !pinned.is_empty()));
    let dir = scratch("pins");
    let through_files = PmOptions {
        block_scratch: Some(dir.clone()),
        ..blocks(400)
    };
    let (files, _) = ProgressiveMesh::from_polygons(&poly, &through_files, &NoProgress).unwrap();
    assert_eq!(files.pins(), pm.pins());
    let _ = std::fs::remove_dir(&dir);
    // The parts of a hierarchy carry its pins, and a record that does not fit is refused.
    let parts = pm.to_parts();
    assert_eq!(
        ProgressiveMesh::from_parts(parts.clone()).unwrap().pins(),
        pm.pins()
    );
    let misfit = meshpyr::pm::Pins::from_passes([(parts.splits.len() + 1, vec![0])]);
    let refused = ProgressiveMesh::from_parts(meshpyr::pm::PmParts {
        pins: Some(misfit),
        ..parts
    });
    assert!(refused.is_err());
    let n = poly.n_vertices();
    let (one_block, _) = ProgressiveMesh::from_polygons(&poly, &blocks(n), &NoProgress).unwrap();
    assert!(
        one_block.pins().is_none(),
        "a mesh in one block pins nothing"
    );
}

/// Per split of `pm`, the ring of its new vertex at its level (PM indices, in circulation
/// order, as the analysis lists them).
fn split_rings(pm: &ProgressiveMesh) -> Vec<Vec<u32>> {
    let mut cursor = pm.cursor();
    let mut rings = vec![Vec::new(); pm.splits().len()];
    for k in (0..rings.len()).rev() {
        let mesh = cursor.mesh();
        let ring = mesh.neighbors(cursor.vertex(pm.n_base_vertices() + k));
        rings[k] = ring.iter().map(|v| v.slot() as u32).collect();
        assert!(cursor.collapse());
    }
    rings
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| x.distance(*y))
        .fold(0.0, f64::max)
}

#[test]
fn a_split_of_a_partitioned_hierarchy_leaves_the_ring_vertices_pinned_in_its_pass_untouched() {
    let poly = load("elephant_holes.ply");
    let (pm, _) = ProgressiveMesh::from_polygons(&poly, &blocks(400), &NoProgress).unwrap();
    let pins = pm.pins().unwrap();
    let rings = split_rings(&pm);
    // Guskov's operator records on the replay, the MCM step on the half-edge cursor.
    let operators: [&dyn Relaxation; 2] =
        [&SecondDifference::default(), &MeanCurvatureStep::default()];
    for op in operators {
        let pyr = DetailPyramid::analyze(&pm, op, &NoProgress).unwrap();
        let mut left_out = 0;
        for (k, ring) in rings.iter().enumerate() {
            let pinned = pins.pinned_at(k);
            let v = (pm.n_base_vertices() + k) as u32;
            let mut free: Vec<u32> = ring
                .iter()
                .copied()
                .filter(|x| pinned.binary_search(x).is_err())
                .collect();
            left_out += ring.len() - free.len();
            // The circulation may start elsewhere on the replay: compare the ring as a set.
            let (first, rest) = pyr.split_details(k).0.split_first().unwrap();
            let mut rest = rest.to_vec();
            rest.sort_unstable();
            free.sort_unstable();
            assert_eq!((*first, rest), (v, free), "split {k}");
        }
        assert!(left_out > 0, "the borders' ring vertices are left out");
        // Each vertex is still set last by the finest split that touches it, to its input
        // value: unit gains reconstruct.
        let err = max_distance(
            &pyr.synthesize(&LevelGains::unit()),
            pm.original_positions(),
        );
        assert!(
            err <= common::closed_loop_bound(&pyr),
            "{}: {err:e}",
            op.name()
        );
    }
    // The same hierarchy without its pins gets the one-process rule: the whole ring.
    let mut bare = pm.clone();
    bare.set_pins(None).unwrap();
    let pyr = DetailPyramid::analyze(&bare, &SecondDifference::default(), &NoProgress).unwrap();
    for (k, ring) in rings.iter().enumerate() {
        assert_eq!(pyr.split_details(k).0.len(), 1 + ring.len(), "split {k}");
    }
}

/// `bytes`' sections, with `tag`'s payload replaced by `payload`.
fn with_section(bytes: &[u8], tag: [u8; 4], payload: Vec<u8>) -> Vec<u8> {
    let c = Container::parse(bytes).unwrap();
    let sections: Vec<Section> = (c.sections.iter())
        .map(|e| Section {
            tag: e.tag,
            flags: e.flags,
            bytes: if e.tag == tag {
                payload.clone()
            } else {
                bytes[e.offset as usize..(e.offset + e.length) as usize].to_vec()
            },
        })
        .collect();
    write_container(c.major, c.minor, &sections)
}

#[test]
fn a_partitioned_pyr_keeps_its_pins_and_filters_to_the_bytes_of_the_mesh() {
    let poly = load("elephant_holes.ply");
    let options = PyramidOptions {
        pm: blocks(400),
        ..PyramidOptions::default()
    };
    let p = Pyramid::build_with(poly.clone(), &options, &NoProgress).unwrap();
    let n = p.pyramid.n_vertices();
    let filters = [
        Filter::new().gain(n / 32, n / 2, 2.0),
        Filter::new().lowpass(n / 8),
        Filter::new().gain(n / 16, n, 0.5).normal_only(),
    ];
    for content in [PyrContent::WithDetails, PyrContent::HierarchyOnly] {
        let bytes = p.to_pyr_bytes_as(content).unwrap().0;
        let c = Container::parse(&bytes).unwrap();
        assert_eq!((c.major, c.minor), (format::MAJOR, 4), "{content:?}");
        let pins = c.sections.iter().find(|e| &e.tag == b"PINS").unwrap();
        assert_eq!(pins.flags, REQUIRED, "an older reader refuses it");
        let data = format::decode(&bytes).unwrap();
        assert_eq!(data.pm.pins(), p.pm.pins(), "{content:?}");
        let (q, from) = data.into_pyramid_with(None, &NoProgress).unwrap();
        let stored = matches!(content, PyrContent::WithDetails);
        assert_eq!(
            from == DetailSource::Stored,
            stored,
            "{content:?}: {from:?}"
        );
        for f in &filters {
            assert_eq!(q.filter(f).positions, p.filter(f).positions, "{content:?}");
        }
    }
    // An edit's file: the same hierarchy with new positions, the same pins, and details
    // analysed under the rule (they fit: the file's pyramid is the stored one).
    let edited = p.filter(&filters[0]).positions;
    let bytes = p.to_pyr_bytes_with_positions(edited).unwrap().0;
    let data = format::decode(&bytes).unwrap();
    assert_eq!(data.pm.pins(), p.pm.pins(), "edit");
    let (_, from) = data.into_pyramid_with(None, &NoProgress).unwrap();
    assert_eq!(from, DetailSource::Stored, "edit");
    // One process: no pins, the 2.1 layout as before.
    let whole = Pyramid::build_with(poly, &PyramidOptions::default(), &NoProgress).unwrap();
    let bytes = whole.to_pyr_bytes().unwrap().0;
    let c = Container::parse(&bytes).unwrap();
    assert_eq!(c.minor, format::MINOR_WITHOUT_CORNERS);
    assert!(c.sections.iter().all(|e| &e.tag != b"PINS"));
}

#[test]
fn a_pyr_whose_pins_pin_a_collapsed_vertex_is_an_error_naming_the_section() {
    let options = PyramidOptions {
        pm: blocks(400),
        ..PyramidOptions::default()
    };
    let p = Pyramid::build_with(load("elephant_holes.ply"), &options, &NoProgress).unwrap();
    let bytes = p.to_pyr_bytes().unwrap().0;
    // One pass over all splits pinning the survivor of the first.
    let mut pins = Vec::new();
    for x in [
        1,
        p.pm.splits().len() as u64,
        1,
        u64::from(p.pm.splits()[0].survivor),
    ] {
        put_uvarint(&mut pins, x);
    }
    let err = format::decode(&with_section(&bytes, *b"PINS", pins)).unwrap_err();
    assert!(err.to_string().contains("pinned"), "{err}");
    let err = format::decode(&with_section(&bytes, *b"PINS", vec![1, 0])).unwrap_err();
    assert!(err.to_string().contains("PINS"), "{err}");
}

/// Per input edge of `pm` (PM indices, each once), the length of the difference between the
/// displacements `filtered − input` at its two ends.
fn displacement_jumps(
    pm: &ProgressiveMesh,
    input: &PolygonMesh,
    filtered: &PolygonMesh,
) -> Vec<([u32; 2], f64)> {
    let moved = |v: u32| {
        let s = pm.pm_to_mesh()[v as usize] as usize;
        filtered.positions[s] - input.positions[s]
    };
    let mut edges: Vec<[u32; 2]> = (pm.finest_faces().iter())
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
        .into_iter()
        .map(|e| (e, moved(e[0]).distance(moved(e[1]))))
        .collect()
}

#[test]
fn a_filter_of_a_partitioned_hierarchy_shows_no_jump_across_the_borders() {
    // A seam would be a border whose vertices move unlike their free neighbours. On the edges
    // between a vertex pinned in the first pass and a free one, the difference of the two
    // displacements under the README's enhancement must stay what it is on the same edges
    // in one process, and on the partitioned filter's other edges.
    let scan = bumpy_scan(160);
    let n = scan.n_vertices();
    let filter = Filter::new().gain(n / 32, n / 2, 2.0);
    let build = |pm: PmOptions| {
        let options = PyramidOptions {
            pm,
            ..PyramidOptions::default()
        };
        Pyramid::build_with(scan.clone(), &options, &NoProgress).unwrap()
    };
    let whole = build(PmOptions::default());
    let whole_filtered = whole.filter(&filter);
    for block in [400, 1600] {
        let parts = build(blocks(block));
        let pins = parts.pm.pins().unwrap();
        // Split order: the first pass is the last.
        let (_, first_pass) = pins.passes().last().unwrap();
        let pinned = |v: u32| first_pass.binary_search(&v).is_ok();
        let jumps = displacement_jumps(&parts.pm, &scan, &parts.filter(&filter));
        let (mut across, mut inside) = (Vec::new(), Vec::new());
        for &([a, b], jump) in &jumps {
            match (pinned(a), pinned(b)) {
                (true, false) | (false, true) => across.push(jump),
                (false, false) => inside.push(jump),
                (true, true) => {}
            }
        }
        // The same edges in one process (its own PM numbering: the input's vertices).
        let to_input = |v: u32| parts.pm.pm_to_mesh()[v as usize];
        let moved_whole =
            |s: u32| whole_filtered.positions[s as usize] - scan.positions[s as usize];
        let mut across_whole: Vec<f64> = (jumps.iter())
            .filter(|([a, b], _)| pinned(*a) != pinned(*b))
            .map(|([a, b], _)| moved_whole(to_input(*a)).distance(moved_whole(to_input(*b))))
            .collect();
        for v in [&mut across, &mut inside, &mut across_whole] {
            v.sort_by(f64::total_cmp);
        }
        let (a, i, w) = (p99(&across), p99(&inside), p99(&across_whole));
        let (am, wm) = (
            across[across.len() - 1],
            across_whole[across_whole.len() - 1],
        );
        // A seam would make jumps of the order of the displacement itself (its p99 is about
        // four times these jumps here).
        let what = format!(
            "blocks of {block}, {} border edges: p99 jump {a:.3e}, on other edges {i:.3e}, \
             one process {w:.3e}; largest {am:.3e}, one process {wm:.3e}",
            across.len()
        );
        assert!(across.len() > 1000, "{what}");
        assert!(a <= 1.2 * i && a <= 1.2 * w && am <= 1.5 * wm, "{what}");
    }
}

#[test]
fn a_mesh_that_fits_one_block_is_one_decimation_of_the_whole() {
    let poly = load("bunny.ply");
    let n = poly.n_vertices();
    let (pm, _) = ProgressiveMesh::from_polygons(&poly, &blocks(n), &NoProgress).unwrap();
    replayed(&pm);
    let (whole, _) =
        ProgressiveMesh::from_polygons(&poly, &PmOptions::default(), &NoProgress).unwrap();
    assert_eq!(pm.n_base_vertices(), whole.n_base_vertices());
}

#[test]
fn a_block_size_below_the_minimum_is_an_error() {
    let poly = load("tripod.ply");
    let err = ProgressiveMesh::from_polygons(&poly, &blocks(3), &NoProgress).unwrap_err();
    assert!(err.to_string().contains("block vertices"), "{err}");
}

/// A scan-like open surface of `n × n` vertices: two scales of bumps, a hash noise a tenth of
/// the spacing, and two round holes.
fn bumpy_scan(n: usize) -> PolygonMesh {
    let h = 1.0 / (n - 1) as f64;
    let noise = |i: usize| {
        let x = (i as u64)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(17);
        (x % 10_000) as f64 / 10_000.0 - 0.5
    };
    let mut positions = Vec::with_capacity(n * n);
    for y in 0..n {
        for x in 0..n {
            let (u, v) = (x as f64 * h, y as f64 * h);
            let z = 0.08 * (6.0 * u).sin() * (5.0 * v).cos()
                + 0.01 * (40.0 * u).sin() * (37.0 * v).sin()
                + 0.1 * h * noise(positions.len());
            positions.push(DVec3::new(u, v, z));
        }
    }
    let hole = |u: f64, v: f64| {
        let d = |cu: f64, cv: f64| (u - cu).hypot(v - cv);
        d(0.3, 0.6) < 0.07 || d(0.7, 0.3) < 0.05
    };
    let id = |x: usize, y: usize| (y * n + x) as u32;
    let mut faces = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            if hole((x as f64 + 0.5) * h, (y as f64 + 0.5) * h) {
                continue;
            }
            faces.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
            faces.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
        }
    }
    PolygonMesh::from_triangle_vec(positions, faces)
}

/// Sorted per-vertex distances between two meshes with the same vertices.
fn distances(a: &PolygonMesh, b: &PolygonMesh) -> Vec<f64> {
    let mut d: Vec<f64> = a
        .positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| p.distance(*q))
        .collect();
    d.sort_by(f64::total_cmp);
    d
}

fn p99(sorted: &[f64]) -> f64 {
    sorted[(sorted.len() - 1) * 99 / 100]
}

#[test]
fn a_filter_on_a_hierarchy_of_small_blocks_adds_no_spikes_at_their_borders() {
    // Issue 47's spike bound on a small scan cut into 16 and 64 blocks: the largest
    // |partitioned − input| stays within 1.5 × the largest |one process − input| under the
    // README's enhancement. The partitioned result differs from the one-process one by less
    // than the filter's own displacement (p99); issue 47's agreement bound, 0.25 of it, is
    // not met (docs/partitioned.md, "How close it is").
    let scan = bumpy_scan(160);
    let n = scan.n_vertices();
    let filter = Filter::new().gain(n / 32, n / 2, 2.0);
    let filtered = |pm: PmOptions| {
        let options = PyramidOptions {
            pm,
            ..PyramidOptions::default()
        };
        Pyramid::build_with(scan.clone(), &options, &NoProgress)
            .unwrap()
            .filter(&filter)
    };
    let whole = filtered(PmOptions::default());
    let moved = distances(&whole, &scan);
    assert!(p99(&moved) > 0.0);
    for block in [1600, 400] {
        let parts = filtered(blocks(block));
        let apart = distances(&parts, &whole);
        let parts_moved = distances(&parts, &scan);
        assert!(
            p99(&apart) < p99(&moved),
            "blocks of {block}: p99 |partitioned − one process| = {:.3e}, \
             p99 |one process − input| = {:.3e}",
            p99(&apart),
            p99(&moved)
        );
        let (max_parts, max_whole) = (parts_moved[n - 1], moved[n - 1]);
        assert!(
            max_parts <= 1.5 * max_whole,
            "blocks of {block}: max |partitioned − input| = {max_parts:.3e}, \
             max |one process − input| = {max_whole:.3e}"
        );
    }
}

/// An open grid with jitter and holes (some faces left out), in several copies side by side.
fn grid_scan(nx: usize, ny: usize, copies: usize, holes: &[bool], jitter: &[f64]) -> Mesh {
    let mut positions = Vec::new();
    let mut tris = Vec::new();
    for copy in 0..copies {
        let base = positions.len() as u32;
        for y in 0..=ny {
            for x in 0..=nx {
                let i = positions.len();
                let j = |k: usize| jitter[(i + k) % jitter.len()];
                let offset = (copy * (nx + 2)) as f64;
                positions.push(DVec3::new(
                    offset + x as f64 + 0.3 * j(0),
                    y as f64 + 0.3 * j(1),
                    j(2),
                ));
            }
        }
        let id = |x: usize, y: usize| base + (y * (nx + 1) + x) as u32;
        for y in 0..ny {
            for x in 0..nx {
                if holes[(y * nx + x + copy) % holes.len()] {
                    continue;
                }
                tris.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
                tris.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
            }
        }
    }
    Mesh::from_triangles(&positions, &tris).unwrap().mesh
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random open grids with holes, in one to three pieces, cut into blocks of 16 to 60
    /// vertices: every split is the exact inverse of its collapse, on the half-edge mesh
    /// (the cursor) and on the stored parts (the validating replay).
    #[test]
    fn splits_of_random_small_blocks_replay_exactly(
        nx in 2usize..14,
        ny in 2usize..14,
        copies in 1usize..4,
        block in 16usize..60,
        holes in prop::collection::vec(prop::bool::weighted(0.1), 29),
        jitter in prop::collection::vec(-1.0f64..1.0, 31),
    ) {
        let mesh = grid_scan(nx, ny, copies, &holes, &jitter);
        prop_assume!(mesh.n_faces() > 0);
        let pm = ProgressiveMesh::build(&mesh, &blocks(block), &NoProgress).unwrap();
        replayed(&pm);
        assert_walks_exactly("grid", &pm);
        let (a, b) = (pm.base_mesh().topology(), mesh.topology());
        prop_assert_eq!(a.components, b.components);
        prop_assert_eq!(a.boundary_loops, b.boundary_loops);
    }
}
