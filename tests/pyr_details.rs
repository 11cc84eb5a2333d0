//! The `.pyr` file's stored details (section `DETL`, format 2.1): within their stated bound,
//! used by readers instead of the detail pass, refused (and recomputed) when they do not fit
//! the file or the operator asked for.

mod common;

use common::data;
use glam::DVec3;
use meshpyr::format::container::{Container, Section, write_container};
use meshpyr::format::{self, FileDetails, PyrData};
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{DetailPyramid, DetailSource, Filter, LevelGains};
use meshpyr::relax::RelaxKind;
use meshpyr::{PyrContent, Pyramid, PyramidOptions};

fn pyramid(name: &str, relax: RelaxKind) -> Pyramid {
    let input = meshpyr::read_mesh(data(name)).unwrap();
    let options = PyramidOptions {
        relaxation: relax.spec(),
        ..Default::default()
    };
    Pyramid::build_with(input, &options, &NoProgress).unwrap()
}

fn decoded(p: &Pyramid) -> PyrData {
    format::decode(&p.to_pyr_bytes().unwrap().0).unwrap()
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length())
        .fold(0.0, f64::max)
}

/// The file stores the pyramid's own quantised details: the same values, whole multiples of a
/// power-of-two step of at most 2^-21 of the bounding-box diagonal, and the exact base.
#[test]
fn stored_details_are_the_pyramids_own() {
    for name in ["joint.ply", "fandisk.ply"] {
        let p = pyramid(name, RelaxKind::SecondDifference);
        let FileDetails::Stored(stored) = decoded(&p).details else {
            panic!("{name}: no usable details");
        };
        let diagonal = p.pyramid.bbox_diagonal();
        assert_eq!(stored.step, p.pyramid.detail_step(), "{name}");
        assert_eq!(stored.step.log2().fract(), 0.0, "{name}");
        assert!(stored.step <= diagonal * 2f64.powi(-21), "{name}");
        let details = stored.details().unwrap();
        let mut at = 0;
        for k in 0..p.pyramid.n_splits() {
            let (_, exact) = p.pyramid.split_details(k);
            let n = exact.len();
            assert_eq!(stored.counts[k] as usize, n, "{name}: split {k}");
            assert!(
                details[at..at + n].iter().copied().eq(exact),
                "{name}: split {k}"
            );
            at += n;
        }
        assert_eq!(
            stored.base,
            p.pyramid.base(),
            "{name}: the base signal is exact"
        );
    }
}

/// Unit gains forced through synthesis reproduce the input within 1e-6 of the diagonal (the
/// closed loop keeps every vertex within √3/2 of a step of its target, docs/algorithms.md §1f),
/// even on the meshes whose frames amplified open-loop rounding a thousandfold.
#[test]
fn unit_gains_reproduce_the_input_within_1e_6_of_the_diagonal() {
    for name in ["fandisk.ply", "mc/mc_bunny_vox40.ply", "joint.ply"] {
        let p = pyramid(name, RelaxKind::SecondDifference);
        let unit = p.pyramid.synthesize(&LevelGains::unit());
        let original = p.pm.original_positions();
        let off = max_distance(&unit, original);
        let bound = 3f64.sqrt() / 2.0 * p.pyramid.detail_step();
        assert!(off <= bound * (1.0 + 1e-9), "{name}: {off:e} > {bound:e}");
        assert!(off < 1e-6 * p.pyramid.bbox_diagonal(), "{name}");
    }
}

/// A pyramid opened from its details holds the analysed pyramid's values, so filters give the
/// same bits (the bound the format promises is 1e-6 of the diagonal); unit gains give the
/// input exactly.
#[test]
fn filters_from_stored_details_give_the_meshs_bits() {
    for (name, relax) in [
        ("fandisk.ply", RelaxKind::SecondDifference),
        ("mc/mc_bunny_vox40.ply", RelaxKind::SecondDifference),
        ("joint.ply", RelaxKind::Mcm),
        ("joint.ply", RelaxKind::Normal),
    ] {
        let p = pyramid(name, relax);
        let (q, from) = decoded(&p).into_pyramid_with(None, &NoProgress).unwrap();
        assert_eq!(from, DetailSource::Stored, "{name}");
        let diagonal = p.pyramid.bbox_diagonal();
        let top = p.pyramid.n_vertices();
        for filter in [
            Filter::new().lowpass(60),
            Filter::new().gain(30, top, 2.0),
            Filter::new().gain(30, top / 2, 0.5).normal_only(),
        ] {
            let (a, b) = (p.filter(&filter), q.filter(&filter));
            assert_eq!(a.positions, b.positions, "{name} {relax:?}");
            assert!(max_distance(&a.positions, &p.input.positions) < diagonal);
        }
        assert_eq!(q.filter(&Filter::new()), p.input, "{name}: unit gains");
        // The spectrum too, straight from the file.
        // The same bits: every energy is a whole multiple of the step's square, summed
        // exactly either way.
        let (exact, stored) = (p.spectrum(), decoded(&p).stored_spectrum(None).unwrap());
        assert_eq!(exact, stored, "{name}");
        assert_eq!(exact.to_csv(), stored.to_csv(), "{name}");
    }
}

/// Asking for another operator than the stored details': they are not used, and the pyramid
/// is that operator's analysis, bit for bit.
#[test]
fn details_of_another_relaxation_are_recomputed() {
    let p = pyramid("joint.ply", RelaxKind::Mcm);
    let d = decoded(&p);
    let wanted = RelaxKind::SecondDifference.spec();
    assert!(d.stored_spectrum(Some(wanted)).is_err());
    let (q, from) = d
        .clone()
        .into_pyramid_with(Some(wanted), &NoProgress)
        .unwrap();
    let DetailSource::Recomputed(why) = from else {
        panic!("stored mcm details used for second differences");
    };
    assert!(why.contains("--relax mcm"), "{why}");
    assert_eq!(q.options.relaxation, wanted);
    let fresh = DetailPyramid::analyze(&d.pm, wanted.operator().as_ref(), &NoProgress).unwrap();
    let unit = LevelGains::unit();
    assert_eq!(q.pyramid.synthesize(&unit), fresh.synthesize(&unit));
}

/// `Pyramid::load_with` opens a saved file with its stored details for its own relaxation,
/// recomputes them for another and says which it did; the pyramid is the same either way as
/// the one `into_pyramid_with` gives.
#[test]
fn load_with_says_whether_the_stored_details_were_used() {
    let p = pyramid("joint.ply", RelaxKind::Mcm);
    let dir = std::env::temp_dir().join(format!("meshpyr-load-with-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("joint.pyr");
    p.save(&path).unwrap();
    let unit = LevelGains::unit();
    let (own, from) = Pyramid::load_with(&path, None, &NoProgress).unwrap();
    assert_eq!(from, DetailSource::Stored);
    assert_eq!(own.pyramid.synthesize(&unit), p.pyramid.synthesize(&unit));
    let wanted = RelaxKind::SecondDifference.spec();
    let (other, from) = Pyramid::load_with(&path, Some(wanted), &NoProgress).unwrap();
    assert!(matches!(&from, DetailSource::Recomputed(why) if why.contains("--relax mcm")));
    assert_eq!(other.options.relaxation, wanted);
    let (expected, _) = decoded(&p)
        .into_pyramid_with(Some(wanted), &NoProgress)
        .unwrap();
    assert_eq!(
        other.pyramid.synthesize(&unit),
        expected.pyramid.synthesize(&unit)
    );
    let missing = Pyramid::load_with(dir.join("none.pyr"), None, &NoProgress);
    assert!(missing.is_err_and(|e| e.to_string().contains("none.pyr")));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The reporting variants give the plain results with what the caller should be told: a band
/// below the coarsest level is warned about, a handle far from every vertex reached nothing.
#[test]
fn filter_and_edit_results_carry_their_warnings_and_reach() {
    let p = pyramid("fandisk.ply", RelaxKind::SecondDifference);
    let levels = p.levels();
    let base = *levels.start();
    let filter = Filter::new().gain(0, base + 10, 2.0);
    let filtered = p.filter_reporting(&filter);
    assert_eq!(filtered.mesh, p.filter(&filter));
    assert_eq!(filtered.warnings, p.band_warnings(&filter));
    assert_eq!(filtered.warnings.len(), 1, "{:?}", filtered.warnings);
    assert!(
        p.filter_reporting(&Filter::new().gain(base, *levels.end(), 2.0))
            .warnings
            .is_empty()
    );
    let near = p.input.positions[0];
    let handles = [
        meshpyr::MoveHandle {
            center: near,
            displacement: DVec3::X * 0.01,
            radius: 0.5,
        },
        meshpyr::MoveHandle {
            center: near + DVec3::splat(1e3),
            displacement: DVec3::X,
            radius: 0.5,
        },
    ];
    let edited = p.edit_reporting(base + 50, &handles, &filter).unwrap();
    assert_eq!(edited.mesh, p.edit(base + 50, &handles, &filter).unwrap());
    assert_eq!(edited.warnings, filtered.warnings);
    assert!(edited.reach[0].points > 0);
    assert_eq!(edited.reach[1].points, 0);
}

/// The file's sections as the container holds them.
fn sections(bytes: &[u8]) -> Vec<Section> {
    let c = Container::parse(bytes).unwrap();
    c.sections
        .iter()
        .map(|e| Section {
            tag: e.tag,
            flags: e.flags,
            bytes: bytes[e.offset as usize..(e.offset + e.length) as usize].to_vec(),
        })
        .collect()
}

/// A `DETL` section moved into another file (the same mesh, other positions) is detected by the
/// checksums it records, and the details are recomputed.
#[test]
fn details_of_another_hierarchy_are_detected_and_recomputed() {
    let p = pyramid("joint.ply", RelaxKind::SecondDifference);
    let moved: Vec<DVec3> = p.input.positions.iter().map(|x| *x * 1.5).collect();
    let (other, _) = p.to_pyr_bytes_with_positions(moved).unwrap();
    let (own, _) = p.to_pyr_bytes().unwrap();
    let detl = |s: &[Section]| s.iter().position(|x| &x.tag == b"DETL").unwrap();
    let mut spliced = sections(&other);
    let theirs = sections(&own);
    let at = detl(&spliced);
    spliced[at] = theirs[detl(&theirs)].clone();
    let bytes = write_container(format::MAJOR, format::MINOR, &spliced);
    let d = format::decode(&bytes).unwrap();
    let FileDetails::Unusable(why) = &d.details else {
        panic!("foreign details accepted");
    };
    assert!(why.contains("another hierarchy"), "{why}");
    let (q, from) = d.clone().into_pyramid_with(None, &NoProgress).unwrap();
    assert!(matches!(from, DetailSource::Recomputed(_)));
    let fresh = format::decode(&other)
        .unwrap()
        .into_pyramid(&NoProgress)
        .unwrap();
    let lowpass = Filter::new().lowpass(40);
    let off = max_distance(
        &q.filter(&lowpass).positions,
        &fresh.filter(&lowpass).positions,
    );
    assert!(off < 1e-9 * q.pyramid.bbox_diagonal(), "{off:e}");
}

/// Details from another version of the analysis (its number is the section's first byte) are
/// not used.
#[test]
fn details_of_another_analysis_version_are_not_used() {
    let p = pyramid("joint.ply", RelaxKind::SecondDifference);
    let mut s = sections(&p.to_pyr_bytes().unwrap().0);
    let detl = s.iter_mut().find(|x| &x.tag == b"DETL").unwrap();
    detl.bytes[0] = detl.bytes[0].wrapping_add(1);
    let d = format::decode(&write_container(format::MAJOR, format::MINOR, &s)).unwrap();
    assert!(
        matches!(&d.details, FileDetails::Unusable(why) if why.contains("analysis version")),
        "{:?}",
        d.details
    );
}

/// A 2.0 reader skips the optional section: the file without it is exactly the file written
/// without details, apart from the version, and `--no-details` writes that.
#[test]
fn the_section_is_optional_and_last() {
    let p = pyramid("joint.ply", RelaxKind::SecondDifference);
    let (with, sizes) = p.to_pyr_bytes().unwrap();
    let (without, plain) = p.to_pyr_bytes_as(PyrContent::HierarchyOnly).unwrap();
    assert_eq!(plain.details, 0);
    assert_eq!(sizes.total, plain.total + sizes.details + 32);
    let mut s = sections(&with);
    let last = s.pop().unwrap();
    assert_eq!((&last.tag, last.flags), (b"DETL", 0));
    assert!(write_container(format::MAJOR, format::MINOR_WITHOUT_CORNERS, &s) == without);
    assert!(matches!(
        format::decode(&without).unwrap().details,
        FileDetails::Absent
    ));
}

/// Corruption inside the section is detected like anywhere else: by its checksum, and by the
/// decoder behind it when the checksum was fixed.
#[test]
fn damaged_details_are_errors() {
    let p = pyramid("joint.ply", RelaxKind::SecondDifference);
    let (bytes, _) = p.to_pyr_bytes().unwrap();
    let c = Container::parse(&bytes).unwrap();
    let e = c.entry(*b"DETL").unwrap();
    let (start, end) = (e.offset as usize, (e.offset + e.length) as usize);
    let mut refused = 0;
    // Every third byte keeps the test short; the fuzzer covers the rest.
    for i in (start..end).step_by(3) {
        let mut b = bytes.clone();
        b[i] ^= 1 << (i % 8);
        assert!(
            matches!(
                format::decode(&b),
                Err(format::FormatError::Checksum { .. })
            ),
            "flip at {i}"
        );
        let fixed = meshpyr::fuzzing::fix_checksums(&b);
        let r = std::panic::catch_unwind(|| meshpyr::fuzzing::fuzz_read_pyr(&fixed));
        assert!(r.is_ok(), "flip at byte {i} panics");
        refused += format::decode(&fixed).is_err() as usize;
    }
    // Flips behind a fixed checksum that break a code, a count or the block structure are
    // refused (others change a base value or a detail, or make the details unusable).
    assert!(refused > 0);
}
