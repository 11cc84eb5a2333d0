//! Replays every committed fuzz corpus file and crash reproducer through the same harness the
//! fuzz targets use (`meshpyr::fuzzing::fuzz_read`), so CI exercises them without cargo-fuzz.

use std::path::Path;

use meshpyr::fuzzing::fuzz_read;
use meshpyr::io::MeshFormat;

fn replay(dir: &str, format: MeshFormat) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut n = 0;
    for kind in ["corpus", "regressions"] {
        let d = root.join(kind).join(dir);
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        let mut files: Vec<_> = rd
            .map(|e| e.unwrap().path())
            .filter(|p| p.is_file())
            .collect();
        files.sort();
        for f in files {
            let bytes = std::fs::read(&f).unwrap();
            let r = std::panic::catch_unwind(|| fuzz_read(format, &bytes));
            assert!(r.is_ok(), "{} panics", f.display());
            n += 1;
        }
    }
    n
}

#[test]
fn replay_read_obj() {
    assert!(replay("read_obj", MeshFormat::Obj) > 0);
}

#[test]
fn replay_read_ply() {
    assert!(replay("read_ply", MeshFormat::Ply) > 0);
}

#[test]
fn replay_read_off() {
    assert!(replay("read_off", MeshFormat::Off) > 0);
}

#[test]
fn replay_read_stl() {
    assert!(replay("read_stl", MeshFormat::Stl) > 0);
}
