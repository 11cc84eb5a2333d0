//! Material libraries (`.mtl`): only what a mesh needs of them, each material's name and
//! diffuse image. The files are read, never rewritten; a mesh without one (read from PLY)
//! gets a small one written for it.

use std::fmt::Write as _;

use crate::io::text::{self, Lines};
use crate::mesh::Material;

/// The materials (`newmtl`) of an MTL file's text with their `map_Kd` images, as written
/// (relative to the library's folder, or absolute). Options before the file name (`-s 1 1 1`,
/// `-clamp on`, …) are skipped; the rest of the line is the file name (spaces included).
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
                let file = without_options(args);
                if let Some(m) = out.last_mut().filter(|_| !file.is_empty()) {
                    m.texture = Some(join(file));
                }
            }
            _ => {}
        }
    }
    out
}

/// The words of a map statement after its options: each `-name` with the numbers or
/// `on`/`off` after it.
fn without_options<'a, 'b>(mut args: &'a [&'b [u8]]) -> &'a [&'b [u8]] {
    while let Some((first, rest)) = args.split_first()
        && first.starts_with(b"-")
        && rest.len() > 1
    {
        args = rest;
        while let Some((value, rest)) = args.split_first()
            && !rest.is_empty()
            && (text::parse_f64(value).is_some() || matches!(*value, b"on" | b"off"))
        {
            args = rest;
        }
    }
    args
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_kd_skips_options_and_keeps_spaces_in_the_file_name() {
        let m =
            parse(b"newmtl a\nmap_Kd -s 1 1 1 -clamp on my image.png\nnewmtl b c\nmap_Kd 7.png\n");
        assert_eq!(m[0].texture.as_deref(), Some("my image.png"));
        assert_eq!(
            (m[1].name.as_str(), m[1].texture.as_deref()),
            ("b c", Some("7.png"))
        );
    }
}
