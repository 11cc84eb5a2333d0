//! `.pyr` files: exact round trips, progressive prefixes, damage handling, golden files.

mod common;

use common::{data, on_threads, position_bits, rich_mesh};
use meshpyr::PyramidOptions;
use meshpyr::format::{self, FormatError};
use meshpyr::fuzzing;
use meshpyr::io;
use meshpyr::mesh::{Mesh, PolygonMesh};
use meshpyr::pm::ProgressiveMesh;
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{DetailPyramid, Pyramid, StoredDetails};
use std::path::PathBuf;

/// The file `meshpyr build` writes: the hierarchy, the exact input and the details.
fn build(input: &PolygonMesh) -> (ProgressiveMesh, Vec<u8>) {
    let built = Mesh::from_polygons(input).unwrap();
    let info = PyramidOptions::default();
    let pm = ProgressiveMesh::build(&built.mesh, &info.pm, &NoProgress).unwrap();
    let op = info.relaxation.operator();
    let pyramid = DetailPyramid::analyze(&pm, op.as_ref(), &NoProgress).unwrap();
    let details = StoredDetails::of(&pyramid, info.relaxation);
    let (bytes, sizes) = format::encode_with_details(input, &pm, &info, Some(&details)).unwrap();
    assert_eq!(sizes.total, bytes.len());
    assert!(sizes.details > 0);
    (pm, bytes)
}

/// A decoded file written again with what it holds (its details too, if it has them).
fn reencode(d: &format::PyrData) -> Vec<u8> {
    let details = match &d.details {
        format::FileDetails::Stored(s) => Some(s),
        _ => None,
    };
    format::encode_with_details(&d.input, &d.pm, &d.info, details)
        .unwrap()
        .0
}

/// Split errors as bit patterns, so that NaN and −0.0 compare exactly.
fn error_bits(errors: &[f32]) -> Vec<u32> {
    errors.iter().map(|e| e.to_bits()).collect()
}

fn tetra() -> PolygonMesh {
    io::read_mesh(data("tetrahedron.ply")).unwrap()
}

/// Everything the user's file holds, compared bit for bit.
fn assert_same_mesh(a: &PolygonMesh, b: &PolygonMesh, name: &str) {
    assert_eq!(position_bits(a), position_bits(b), "{name}: position bits");
    assert_eq!(a.face_starts, b.face_starts, "{name}: polygons");
    assert_eq!(a.face_indices, b.face_indices, "{name}: polygons");
    assert_eq!(a.position_type, b.position_type, "{name}: position type");
    assert_eq!(a.vertex_attributes, b.vertex_attributes, "{name}");
    assert_eq!(a.face_attributes, b.face_attributes, "{name}");
    assert_eq!(a.extra_elements, b.extra_elements, "{name}");
    assert_eq!(a.comments, b.comments, "{name}");
}

fn meshes() -> Vec<(String, PolygonMesh)> {
    let mut v: Vec<(String, PolygonMesh)> = [
        "tetrahedron.ply",
        "joint.ply",
        "spider_assimp.ply",
        "cube_quad_poly.ply",
        "elephant_holes.ply",
        "planar_pymeshfix_vtk.ply",
    ]
    .iter()
    .map(|n| (n.to_string(), io::read_mesh(data(n)).unwrap()))
    .collect();
    v.push(("rich_mesh".into(), rich_mesh()));
    v
}

#[test]
fn decode_restores_input_and_hierarchy_exactly() {
    for (name, input) in meshes() {
        let (pm, bytes) = build(&input);
        let d = format::decode(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_same_mesh(&input, &d.input, &name);
        assert_eq!(d.input, input, "{name}");
        assert_eq!(d.pm.splits(), pm.splits(), "{name}");
        assert_eq!(d.pm.finest_faces(), pm.finest_faces(), "{name}");
        assert_eq!(d.pm.pm_to_mesh(), pm.pm_to_mesh(), "{name}");
        assert_eq!(d.pm.n_base_faces(), pm.n_base_faces(), "{name}");
        // Loading never builds the half-edge mesh (clean triangle meshes such as tetrahedron,
        // joint and elephant_holes take their faces off the input, the others off the
        // builder's corner table); what is built on demand, and the map back the pyramid
        // keeps, must be what `build` built.
        let (b, want) = (d.built().unwrap(), Mesh::from_polygons(&input).unwrap());
        assert_eq!(b.mesh.to_triangles(), want.mesh.to_triangles(), "{name}");
        assert_eq!(b.source, want.source, "{name}");
        let scan = d.clone().into_pyramid(&meshpyr::NoProgress).unwrap();
        assert_eq!(scan.source, want.source, "{name}");
        let bits = |p: &ProgressiveMesh| -> Vec<[u64; 3]> {
            p.original_positions()
                .iter()
                .map(|x| x.to_array().map(f64::to_bits))
                .collect()
        };
        assert_eq!(bits(&d.pm), bits(&pm), "{name}");
        assert_eq!(
            error_bits(d.pm.split_errors()),
            error_bits(pm.split_errors())
        );
        // write → read → write is byte-identical, details included
        assert!(
            matches!(d.details, format::FileDetails::Stored(_)),
            "{name}"
        );
        assert!(
            reencode(&d) == bytes,
            "{name}: re-encoding changed the bytes"
        );
    }
}

/// A file read in place (mapped, its pages handed back as they are decoded) decodes to what
/// its bytes decode to, details included; an empty or foreign file gives the usual errors.
#[test]
fn a_file_read_in_place_decodes_as_its_bytes() {
    let dir = tempfile::tempdir().unwrap();
    for (name, input) in meshes() {
        let (_, bytes) = build(&input);
        let path = dir.path().join(format!("{name}.pyr"));
        std::fs::write(&path, &bytes).unwrap();
        let file = format::PyrFile::open(&path).unwrap();
        assert_eq!(file.bytes(), &bytes[..], "{name}");
        let (mapped, read) = (file.decode().unwrap(), format::decode(&bytes).unwrap());
        assert_eq!(mapped.input, read.input, "{name}");
        assert_eq!(mapped.pm.splits(), read.pm.splits(), "{name}");
        let (format::FileDetails::Stored(a), format::FileDetails::Stored(b)) =
            (&mapped.details, &read.details)
        else {
            panic!("{name}: no stored details");
        };
        assert_eq!(a, b, "{name}");
        assert!(reencode(&mapped) == bytes, "{name}");
    }
    for (content, error) in [
        (&b""[..], "byte 0: file is truncated inside magic"),
        (
            b"ply\nformat ascii 1.0\n",
            "not a .pyr file (bad signature)",
        ),
    ] {
        let other = dir.path().join("other.pyr");
        std::fs::write(&other, content).unwrap();
        let got = format::PyrFile::open(&other).unwrap().decode().unwrap_err();
        assert_eq!(got.to_string(), error);
    }
}

/// Saving consumes the pyramid section by section (its detail pyramid dropped before the
/// hierarchy is encoded) and writes the bytes a pyramid gathers in memory.
#[test]
fn a_pyramid_written_section_by_section_is_the_file_gathered_in_memory() {
    let input = rich_mesh();
    let pyramid = Pyramid::build(&input).unwrap();
    let (bytes, sizes) = pyramid.to_pyr_bytes().unwrap();
    let mut written = Vec::new();
    let encoded = pyramid.encode_as(meshpyr::PyrContent::WithDetails).unwrap();
    encoded.write_to(&mut written).unwrap();
    assert!(written == bytes);
    let (consumed, pm) = pyramid
        .into_encoded(meshpyr::PyrContent::WithDetails)
        .unwrap();
    assert_eq!(consumed.sizes, sizes);
    assert_eq!(sizes.total, bytes.len());
    assert!(consumed.into_bytes() == bytes);
    assert_eq!(pm.n_vertices(), input.n_vertices());
}

#[test]
fn f64_positions_are_kept_exactly() {
    let mut m = io::read_mesh(data("joint.ply")).unwrap();
    for p in &mut m.positions {
        p.x += 1e-9 * p.y; // not representable as f32
    }
    m.position_type = Some(meshpyr::mesh::ScalarType::F64);
    let (_, bytes) = build(&m);
    let d = format::decode(&bytes).unwrap();
    assert_same_mesh(&m, &d.input, "joint f64");
}

#[test]
fn loaded_pyramid_has_identical_details_and_synthesis() {
    let input = io::read_mesh(data("joint.ply")).unwrap();
    let scan = Pyramid::build_with(input.clone(), &Default::default(), &NoProgress).unwrap();
    let (bytes, _) = format::encode(&scan.input, &scan.pm, &PyramidOptions::default()).unwrap();
    let loaded = format::decode(&bytes)
        .unwrap()
        .into_pyramid(&NoProgress)
        .unwrap();
    let (a, b) = (&scan.pyramid, &loaded.pyramid);
    assert_eq!(a.n_splits(), b.n_splits());
    let bits = |v: &[glam::DVec3]| -> Vec<[u64; 3]> {
        v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
    };
    assert_eq!(bits(a.base()), bits(b.base()));
    for k in 0..a.n_splits() {
        let (ia, da) = a.split_details(k);
        let (ib, db) = b.split_details(k);
        assert_eq!(ia, ib);
        let (da, db): (Vec<_>, Vec<_>) = (da.collect(), db.collect());
        assert_eq!(bits(&da), bits(&db), "details of split {k}");
    }
    let gains = meshpyr::pyramid::Filter::default()
        .lowpass(meshpyr::pyramid::LevelSpec::Vertices(60))
        .resolve(a.surface_area());
    assert_eq!(bits(&a.synthesize(&gains)), bits(&b.synthesize(&gains)));
    let _ = DetailPyramid::analyze; // the loader's path
}

#[test]
fn levels_match_the_progressive_mesh() {
    let input = io::read_mesh(data("joint.ply")).unwrap();
    let (pm, bytes) = build(&input);
    for level in [
        pm.n_base_vertices(),
        pm.n_base_vertices() + 7,
        150,
        pm.n_vertices(),
    ] {
        let l = format::read_level(&bytes, Some(level)).unwrap();
        assert_eq!(l.level, level);
        assert!(!l.truncated);
        assert_eq!(l.positions, pm.original_positions()[..level]);
        assert_eq!(
            canonical(&l.triangles),
            canonical(&pm.level_triangles(level)),
            "level {level}"
        );
    }
}

#[test]
fn the_level_within_a_triangle_budget_is_the_progressive_meshs_and_read_from_the_prefix() {
    let input = io::read_mesh(data("joint.ply")).unwrap();
    let (pm, bytes) = build(&input);
    let finest = pm.finest_faces().len();
    for budget in [
        0,
        pm.n_base_faces(),
        101,
        400,
        finest - 1,
        finest,
        10 * finest,
    ] {
        let l = format::read_level_within(&bytes, budget).unwrap();
        let level = pm.level_for_faces(budget);
        assert_eq!(l.level, level, "budget {budget}");
        assert_eq!(l.finest, pm.n_vertices());
        assert_eq!(l.positions, pm.original_positions()[..level]);
        assert_eq!(
            canonical(&l.triangles),
            canonical(&pm.level_triangles(level))
        );
        assert!(
            l.triangles.len() <= budget.max(pm.n_base_faces()),
            "budget {budget}"
        );
    }
    // A truncated file gives at most the level it still holds, within the budget.
    let l = format::read_level_within(&bytes[..bytes.len() / 2], 400).unwrap();
    assert!(l.truncated && l.level <= pm.level_for_faces(400));
    assert_eq!(l.positions, pm.original_positions()[..l.level]);
    assert!(l.triangles.len() <= 400);
}

/// Triangles as a sorted list, each turned to start at its smallest index.
fn canonical(t: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = t
        .iter()
        .map(|t| {
            let k = (0..3).min_by_key(|&i| t[i]).unwrap();
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        })
        .collect();
    v.sort();
    v
}

#[test]
fn every_truncation_gives_a_prefix_level_or_a_clean_error() {
    for name in ["tetrahedron.ply", "joint.ply"] {
        let input = io::read_mesh(data(name)).unwrap();
        let (pm, bytes) = build(&input);
        let mut levels = Vec::new();
        for cut in 0..bytes.len() {
            let part = &bytes[..cut];
            assert!(
                format::decode(part).is_err(),
                "{name}: decode of {cut} bytes"
            );
            match format::read_level(part, None) {
                Ok(l) => {
                    assert!(l.truncated, "{name}: cut {cut} not flagged");
                    assert_eq!(l.positions, pm.original_positions()[..l.level]);
                    levels.push(l.level);
                }
                Err(FormatError::Truncated { .. }) => {}
                Err(e) => panic!("{name}: cut at {cut}: unexpected {e}"),
            }
        }
        // Levels only grow as more of the file arrives.
        assert!(levels.windows(2).all(|w| w[0] <= w[1]));
        assert!(!levels.is_empty(), "{name}: no prefix was readable");
    }
}

#[test]
fn bit_flips_are_errors_or_harmless() {
    let (_, bytes) = build(&io::read_mesh(data("joint.ply")).unwrap());
    let original = format::decode(&bytes).unwrap().input;
    for i in 0..bytes.len() {
        // One bit per byte, varying which, keeps the test short.
        {
            let bit = i % 8;
            let mut b = bytes.clone();
            b[i] ^= 1 << bit;
            if let Ok(d) = format::decode(&b) {
                // Only bytes no checksum covers (reserved fields) may change silently.
                assert_eq!(
                    d.input, original,
                    "flip at byte {i} bit {bit} changed the data"
                );
            }
            let _ = format::read_level(&b, Some(100));
        }
    }
}

/// Damage behind valid checksums (as if the writer were buggy, or the damage were deliberate):
/// the decoders themselves must refuse it or produce a consistent result, never panic.
#[test]
fn damage_with_fixed_checksums_never_panics() {
    let (_, bytes) = build(&io::read_mesh(data("joint.ply")).unwrap());
    assert!(fuzzing::fix_checksums(&bytes) == bytes);
    let mut accepted = 0;
    // Every 7th byte keeps the test at a few seconds; the fuzzer covers the rest.
    for i in (24..bytes.len()).step_by(7) {
        let mut b = bytes.clone();
        b[i] ^= 1 << (i % 8);
        let b = fuzzing::fix_checksums(&b);
        let r = std::panic::catch_unwind(|| fuzzing::fuzz_read_pyr(&b));
        assert!(r.is_ok(), "flip at byte {i} panics");
        accepted += format::decode(&b).is_ok() as usize;
    }
    // Some flips only change a position or an attribute value: those files are valid.
    assert!(accepted > 0);
}

#[test]
fn wrong_version_and_unknown_required_sections_are_refused() {
    let (_, bytes) = build(&tetra());
    let c = meshpyr::format::container::Container::parse(&bytes).unwrap();
    let mut sections: Vec<meshpyr::format::container::Section> = c
        .sections
        .iter()
        .map(|e| meshpyr::format::container::Section {
            tag: e.tag,
            flags: e.flags,
            bytes: bytes[e.offset as usize..(e.offset + e.length) as usize].to_vec(),
        })
        .collect();
    let newer = meshpyr::format::container::write_container(format::MAJOR + 1, 0, &sections);
    assert!(matches!(
        format::decode(&newer),
        Err(FormatError::Version { major, .. }) if major == format::MAJOR + 1
    ));
    let older = meshpyr::format::container::write_container(format::OLDEST_MAJOR - 1, 0, &sections);
    assert!(matches!(
        format::decode(&older),
        Err(FormatError::Version { major: 0, .. })
    ));
    // A newer minor with an extra optional section still reads.
    sections.push(meshpyr::format::container::Section {
        tag: *b"XTRA",
        flags: 0,
        bytes: vec![1, 2, 3],
    });
    let minor = meshpyr::format::container::write_container(format::MAJOR, 7, &sections);
    assert_eq!(format::decode(&minor).unwrap().input, tetra());
    sections.last_mut().unwrap().flags = meshpyr::format::container::REQUIRED;
    let req = meshpyr::format::container::write_container(format::MAJOR, 7, &sections);
    assert!(matches!(
        format::decode(&req),
        Err(FormatError::Version { .. })
    ));
    assert!(matches!(
        format::decode(b"ply\nformat"),
        Err(FormatError::NotPyr)
    ));
}

fn golden(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("formats/golden")
        .join(name)
}

/// The golden files pin the byte layout. If this fails, the encoder's output changed: if that
/// was deliberate, bump the format version (major for incompatible, minor for additions, see
/// formats/pyr.md) and regenerate with `MESHPYR_REGENERATE_GOLDEN=1 cargo test --test pyr_format`.
#[test]
fn golden_files_are_byte_identical() {
    for (file, mesh) in [("tetra.pyr", "tetrahedron.ply"), ("joint.pyr", "joint.ply")] {
        let (_, bytes) = build(&io::read_mesh(data(mesh)).unwrap());
        let path = golden(file);
        if std::env::var_os("MESHPYR_REGENERATE_GOLDEN").is_some() {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &bytes).unwrap();
        }
        let stored = std::fs::read(&path).unwrap();
        assert!(
            stored == bytes,
            "{file}: the .pyr encoder no longer writes the golden bytes. If the layout change is \
             deliberate, bump the version in src/format/pyr.rs and formats/pyr.md, then regenerate \
             with MESHPYR_REGENERATE_GOLDEN=1 cargo test --test pyr_format"
        );
        // And the stored file still decodes to the mesh.
        let d = format::decode(&stored).unwrap();
        assert_eq!(d.input, io::read_mesh(data(mesh)).unwrap());
    }
}

/// Files of format 2.0 (no details) still load: the golden files of 2.0 decode to the input
/// mesh without details, and their pyramid is the analysis' (the details recomputed).
#[test]
fn format_2_0_files_still_load() {
    for (file, mesh) in [("tetra.pyr", "tetrahedron.ply"), ("joint.pyr", "joint.ply")] {
        let old = std::fs::read(golden(&format!("v2.0/{file}"))).unwrap();
        assert_eq!(&old[8..12], &[2, 0, 0, 0], "{file}: not a 2.0 file");
        let input = io::read_mesh(data(mesh)).unwrap();
        let d = format::decode(&old).unwrap();
        assert_same_mesh(&input, &d.input, file);
        assert!(matches!(d.details, format::FileDetails::Absent), "{file}");
        let (pyramid, from) = d.clone().into_pyramid_with(None, &NoProgress).unwrap();
        assert_eq!(
            from,
            meshpyr::pyramid::DetailSource::Recomputed(meshpyr::pyramid::NO_STORED_DETAILS.into())
        );
        let op = d.info.relaxation.operator();
        let fresh = DetailPyramid::analyze(&d.pm, op.as_ref(), &NoProgress).unwrap();
        let unit = meshpyr::pyramid::LevelGains::unit();
        assert_eq!(pyramid.pyramid.synthesize(&unit), fresh.synthesize(&unit));
    }
}

/// Files of format 1.0 (split errors as raw f32) still load: the golden files of 1.0 decode to
/// the input mesh and a complete hierarchy, and saving that hierarchy again writes a current
/// file that decodes to the same splits and error bits. (They hold the hierarchy the builder
/// made when they were written, so they are compared with themselves, not with a fresh build.)
#[test]
fn format_1_files_still_load() {
    for (file, mesh) in [("tetra.pyr", "tetrahedron.ply"), ("joint.pyr", "joint.ply")] {
        let old = std::fs::read(golden(&format!("v1/{file}"))).unwrap();
        assert_eq!(&old[8..10], &1u16.to_le_bytes(), "{file}: not a 1.x file");
        let input = io::read_mesh(data(mesh)).unwrap();
        let d = format::decode(&old).unwrap();
        assert_same_mesh(&input, &d.input, file);
        assert_eq!(d.pm.n_vertices(), input.n_vertices(), "{file}");
        let level = format::read_level(&old, None).unwrap();
        assert_eq!(level.level, d.pm.n_vertices(), "{file}");
        let (again, _) = format::encode(&d.input, &d.pm, &d.info).unwrap();
        assert_eq!(&again[8..12], &[2, 0, 1, 0], "{file}: not saved as 2.1");
        let resaved = format::decode(&again).unwrap();
        assert_eq!(resaved.pm.splits(), d.pm.splits(), "{file}");
        assert_eq!(
            error_bits(resaved.pm.split_errors()),
            error_bits(d.pm.split_errors()),
            "{file}"
        );
    }
}

/// The error deltas are exact for any bit pattern: negative, zero, subnormal, infinite and NaN
/// errors, and jumps across the whole `u32` range, come back with the same bits.
#[test]
fn split_errors_round_trip_for_any_bits() {
    let input = io::read_mesh(data("joint.ply")).unwrap();
    let (pm, _) = build(&input);
    let odd = [
        0u32,
        u32::MAX,
        f32::NAN.to_bits(),
        f32::INFINITY.to_bits(),
        (-0.0f32).to_bits(),
        1,
        0x8000_0001,
        (-3.5f32).to_bits(),
        0x7fff_ffff,
    ];
    let errors: Vec<f32> = (0..pm.splits().len())
        .map(|i| f32::from_bits(odd[i % odd.len()].wrapping_add(i as u32 / odd.len() as u32)))
        .collect();
    let parts = meshpyr::pm::PmParts {
        errors: errors.clone(),
        ..pm.to_parts()
    };
    let odd_pm = ProgressiveMesh::from_parts(parts).unwrap();
    let (bytes, _) = format::encode(&input, &odd_pm, &PyramidOptions::default()).unwrap();
    let d = format::decode(&bytes).unwrap();
    assert_eq!(error_bits(d.pm.split_errors()), error_bits(&errors));
}

/// A split error whose running value leaves the `u32` range, and bytes after a block's errors,
/// are typed errors naming the problem (the checksums are fixed, so the decoder sees them).
#[test]
fn damaged_split_errors_are_typed_errors() {
    use meshpyr::format::container::{Container, Section, write_container};
    use meshpyr::format::varint::{ByteReader, put_ivarint};
    let (_, bytes) = build(&io::read_mesh(data("joint.ply")).unwrap());
    let c = Container::parse(&bytes).unwrap();
    // (payload, offset of its errors, split count) → new payload.
    type Edit<'a> = &'a dyn Fn(&[u8], usize, usize) -> Vec<u8>;
    let with_payload = |edit: Edit<'_>| {
        let sections: Vec<Section> = c
            .sections
            .iter()
            .map(|e| {
                let mut b = bytes[e.offset as usize..(e.offset + e.length) as usize].to_vec();
                if &e.tag == b"SPLT" {
                    // One block: count, length, CRC, then records, errors, positions.
                    let count = u32::from_le_bytes(b[0..4].try_into().unwrap()) as usize;
                    let payload = &b[12..];
                    let mut r = ByteReader::new(payload, 0);
                    for _ in 0..3 * count {
                        r.uvarint("record").unwrap();
                    }
                    let payload = edit(payload, r.offset() as usize, count);
                    b.truncate(4);
                    b.extend_from_slice(&(payload.len() as u32).to_le_bytes());
                    b.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
                    b.extend_from_slice(&payload);
                }
                Section {
                    tag: e.tag,
                    flags: e.flags,
                    bytes: b,
                }
            })
            .collect();
        write_container(format::MAJOR, format::MINOR, &sections)
    };
    // Unchanged payload: still decodes (the harness itself is sound).
    assert!(format::decode(&with_payload(&|p, _, _| p.to_vec())).is_ok());
    // The first error's delta replaced by −1: the running value goes below 0.
    let negative = with_payload(&|p, errors_at, _| {
        let mut r = ByteReader::new(&p[errors_at..], 0);
        r.ivarint("error").unwrap();
        let mut out = p[..errors_at].to_vec();
        put_ivarint(&mut out, -1);
        out.extend_from_slice(&p[errors_at + r.offset() as usize..]);
        out
    });
    let err = format::decode(&negative).unwrap_err();
    assert!(matches!(err, FormatError::Corrupt { .. }), "{err}");
    assert!(
        err.to_string().contains("split error out of range"),
        "{err}"
    );
    // A byte between the errors and the positions (joint's positions are f32: 12 bytes each).
    let trailing = with_payload(&|p, _, count| {
        let cut = p.len() - 12 * count;
        let mut out = p[..cut].to_vec();
        out.push(0);
        out.extend_from_slice(&p[cut..]);
        out
    });
    let err = format::decode(&trailing).unwrap_err();
    assert!(
        err.to_string().contains("trailing bytes in split block"),
        "{err}"
    );
}

#[test]
fn fuzz_corpus_replays() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/read_pyr");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        let bytes = std::fs::read(&p).unwrap();
        let r = std::panic::catch_unwind(|| fuzzing::fuzz_read_pyr(&bytes));
        assert!(r.is_ok(), "{} panics", p.display());
        n += 1;
    }
    assert!(n > 0);
}

#[test]
#[ignore = "bunny: a few seconds in release; run with --ignored"]
fn bunny_round_trip() {
    let input = io::read_mesh(data("bunny.ply")).unwrap();
    let (_, bytes) = build(&input);
    let d = format::decode(&bytes).unwrap();
    assert_eq!(d.input, input);
}

/// The number of sections and the offset of the `SPLT` entry in the section table.
fn split_entry(bytes: &[u8]) -> (usize, usize) {
    let n = u32::from_le_bytes(bytes[16..20].try_into().unwrap()) as usize;
    let entry = (0..n)
        .map(|i| 24 + 32 * i)
        .find(|&e| &bytes[e..e + 4] == b"SPLT")
        .unwrap();
    (n, entry)
}

/// The `SPLT` section's (offset, length) and the payload range of each of its blocks.
fn split_blocks(bytes: &[u8]) -> ((usize, usize), Vec<std::ops::Range<usize>>) {
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap()) as usize;
    let (_, entry) = split_entry(bytes);
    let (off, len) = (u64_at(entry + 8), u64_at(entry + 16));
    let mut blocks = Vec::new();
    let mut at = off;
    while at < off + len {
        let payload = u32_at(at + 4);
        blocks.push(at + 12..at + 12 + payload);
        at += 12 + payload;
    }
    ((off, len), blocks)
}

/// Recomputes the `SPLT` section checksum and the header checksum, leaving the block
/// checksums as they are.
fn fix_section_checksums(bytes: &mut [u8]) {
    let (n, entry) = split_entry(bytes);
    let ((off, len), _) = split_blocks(bytes);
    let crc = crc32fast::hash(&bytes[off..off + len]);
    bytes[entry + 24..entry + 28].copy_from_slice(&crc.to_le_bytes());
    let mut h = crc32fast::Hasher::new();
    h.update(&bytes[..20]);
    h.update(&bytes[24..24 + 32 * n]);
    let crc = h.finalize();
    bytes[20..24].copy_from_slice(&crc.to_le_bytes());
}

/// The split blocks are decoded by whichever thread claims them first (the replaying one, or
/// the other core ahead of it): the result, and which error a damaged file reports (the
/// first a sequential reader meets), must not depend on the thread count.
#[test]
fn split_blocks_decode_the_same_on_any_thread_count() {
    let input = io::read_mesh(data("fandisk.ply")).unwrap();
    let (_, bytes) = build(&input);
    let (_, blocks) = split_blocks(&bytes);
    assert!(
        blocks.len() >= 2,
        "fandisk has {} split blocks",
        blocks.len()
    );

    // Block 0's records damaged behind valid checksums until replaying them fails (the
    // wing codes decode, but point past the survivor's ring); then block 1's checksum broken
    // as well: the error must still be block 0's, met before block 1 is looked at.
    let mut first = None;
    for i in blocks[0].clone() {
        let mut b = bytes.clone();
        b[i] ^= 0x02;
        let b = fuzzing::fix_checksums(&b);
        if let Err(e) = format::decode(&b)
            && e.to_string().contains("wing index past")
        {
            first = Some((b, e));
            break;
        }
    }
    let (damaged0, error0) = first.expect("some damage in block 0 fails its replay");
    let mut both = damaged0.clone();
    both[blocks[1].start] ^= 1;
    fix_section_checksums(&mut both);
    let mut only1 = bytes.clone();
    only1[blocks[1].start] ^= 1;
    fix_section_checksums(&mut only1);

    let run = |threads: usize| {
        on_threads(threads, || {
            let d = format::decode(&bytes).unwrap();
            let again = reencode(&d);
            (
                again,
                format::decode(&both).err(),
                format::decode(&only1).err(),
                format::read_level(&bytes, None).unwrap().triangles,
            )
        })
    };
    let one = run(1);
    assert_eq!(one.0, bytes, "decode then encode is byte-identical");
    assert_eq!(one.1.as_ref(), Some(&error0));
    assert!(
        matches!(one.2, Some(FormatError::Checksum { offset, .. }) if offset as usize == blocks[1].start - 12),
        "{:?}",
        one.2
    );
    for threads in [2, 3] {
        assert!(run(threads) == one, "{threads} threads");
    }
}
