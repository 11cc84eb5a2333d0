//! Material libraries (`.mtl`): only what a mesh needs of them, each material's name and
//! diffuse image. The files are read, never rewritten; a mesh without one (read from PLY)
//! gets a small one written for it.

use std::fmt::Write as _;

use crate::io::text::{self, Lines};
use crate::mesh::Material;

/// The materials (`newmtl`) of an MTL file's text with their `map_Kd` images, as written
/// (relative to the library's folder, or absolute). Options before the file name (`-s 1 1 1`,
/// `-bm 0.5`, …) are skipped: the image is the last word.
pub(crate) fn parse(bytes: &[u8]) -> Vec<Material> {
    let mut out: Vec<Material> = Vec::new();
    for (_, line) in Lines::new(bytes, 1) {
        let data = line.split(|&b| b == b'#').next().unwrap_or_default();
        let toks: Vec<&[u8]> = text::tokens(data).collect();
        match toks.split_first() {
            Some((&b"newmtl", name)) if !name.is_empty() => out.push(Material {
                name: join(name),
                texture: None,
            }),
            Some((&b"map_Kd", args)) => {
                if let (Some(m), Some(file)) = (out.last_mut(), args.last()) {
                    m.texture = Some(String::from_utf8_lossy(file).into_owned());
                }
            }
            _ => {}
        }
    }
    out
}

/// Words joined by single spaces (how the OBJ reader names a `usemtl` material).
fn join(words: &[&[u8]]) -> String {
    let words: Vec<String> = words
        .iter()
        .map(|w| String::from_utf8_lossy(w).into_owned())
        .collect();
    words.join(" ")
}

/// An MTL file for `materials` (name and diffuse image each), for a mesh that has materials
/// but no library.
pub(crate) fn write(materials: &[Material]) -> String {
    let mut s = String::from("# materials of a mesh written by meshpyr\n");
    for m in materials {
        let _ = writeln!(s, "newmtl {}", m.name);
        if let Some(t) = &m.texture {
            let _ = writeln!(s, "map_Kd {t}");
        }
    }
    s
}
