//! The files a textured mesh names: material libraries and images.
//!
//! Policy: they are referenced, never copied or rewritten. A mesh read from a path records
//! its folder ([`Materials::folder`]); a mesh written into another folder gets its relative
//! references rewritten to reach the same files from there (absolute ones stay as they are);
//! bytes whose folder is not known (the editor's downloads) get them absolute.
//! A mesh with materials but no library (read from PLY) gets `NAME.mtl` written beside an OBJ
//! output, naming each material's image. A missing library or image, or a `usemtl` that no
//! library defines, is a warning: exporters often write such files, and the mesh is whole
//! without them.

use std::path::{Component, Path, PathBuf};

use super::MeshFormat;
use super::obj::mtl;
use crate::mesh::{Materials, PolygonMesh};

/// Records the folder of a mesh read from `path`, reads its material libraries (OBJ) for their
/// images, and says what is missing (one line each).
pub(crate) fn resolve(mesh: &mut PolygonMesh, path: &Path, format: MeshFormat) -> Vec<String> {
    if mesh.materials.is_empty() {
        return Vec::new();
    }
    let folder = absolute_folder(path);
    let mut warnings = Vec::new();
    if format == MeshFormat::Obj {
        read_libraries(mesh, &folder, &mut warnings);
    }
    for t in mesh
        .materials
        .list
        .iter()
        .filter_map(|m| m.texture.as_ref())
    {
        if !folder.join(t).is_file() {
            warnings.push(format!("image {t} not found"));
        }
    }
    mesh.materials.folder = Some(folder);
    warnings
}

/// Gives each material of an OBJ mesh the image its library names.
fn read_libraries(mesh: &mut PolygonMesh, folder: &Path, warnings: &mut Vec<String>) {
    let mut defined = Vec::new();
    for lib in &mesh.materials.libraries {
        let file = folder.join(lib);
        match std::fs::read(&file) {
            Ok(bytes) => {
                let lib_dir = Path::new(lib).parent().unwrap_or(Path::new(""));
                for mut m in mtl::parse(&bytes) {
                    m.texture = m.texture.map(|t| slashed(&lib_dir.join(t)));
                    defined.push(m);
                }
            }
            Err(e) => warnings.push(format!("material library {lib}: {e}")),
        }
    }
    let any_library = !mesh.materials.libraries.is_empty();
    for m in &mut mesh.materials.list {
        match defined.iter().find(|d| d.name == m.name) {
            Some(d) if m.texture.is_none() => m.texture = d.texture.clone(),
            Some(_) => {}
            None if any_library => warnings.push(format!(
                "material {} is used but no material library defines it",
                m.name
            )),
            None => warnings.push(format!(
                "material {} is used but the file names no material library",
                m.name
            )),
        }
    }
}

/// The absolute folder of `path`, without `.` and `..` components.
fn absolute_folder(path: &Path) -> PathBuf {
    let folder = path.parent().unwrap_or(Path::new(""));
    let folder = if folder.as_os_str().is_empty() {
        Path::new(".")
    } else {
        folder
    };
    normalized(&std::path::absolute(folder).unwrap_or_else(|_| folder.to_path_buf()))
}

/// `path` with `.` removed and `..` applied to the component before it (no file system access:
/// a reference is resolved the way a viewer resolves it, by text).
fn normalized(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// `path` with `/` separators, as OBJ and PLY files write them on every system.
fn slashed(path: &Path) -> String {
    let parts: Vec<String> = path
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let joined = parts.join("/");
    if path.has_root() {
        format!("/{}", joined.trim_start_matches('/'))
    } else {
        joined
    }
}

/// The relative path from the folder `from` to `to` (both absolute and normalised).
fn relative(to: &Path, from: &Path) -> PathBuf {
    let (t, f): (Vec<Component>, Vec<Component>) =
        (to.components().collect(), from.components().collect());
    let common = t.iter().zip(&f).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..f.len() {
        out.push("..");
    }
    for c in &t[common..] {
        out.push(c);
    }
    out
}

/// The mesh's materials with their relative paths rewritten for a file written at `out`.
pub(crate) fn rebased(materials: &Materials, out: &Path) -> Materials {
    rebased_to(materials, Some(absolute_folder(out)))
}

/// The mesh's materials with their relative paths made absolute, for bytes whose folder is
/// not known (a download): they reach the same files from any folder on this machine.
pub(crate) fn anchored(materials: &Materials) -> Materials {
    rebased_to(materials, None)
}

/// The materials' relative paths rewritten to reach the same files from the folder `to`, or
/// absolute without one.
fn rebased_to(materials: &Materials, to: Option<PathBuf>) -> Materials {
    let Some(from) = &materials.folder else {
        return materials.clone();
    };
    let rebase = |p: &String| -> String {
        if Path::new(p).is_absolute() || Some(from) == to.as_ref() {
            return p.clone();
        }
        let file = normalized(&from.join(p));
        slashed(&to.as_ref().map_or(file.clone(), |to| relative(&file, to)))
    };
    let mut m = materials.clone();
    m.libraries = m.libraries.iter().map(rebase).collect();
    for mat in &mut m.list {
        mat.texture = mat.texture.as_ref().map(rebase);
    }
    if to.is_some() {
        m.folder = to;
    }
    m
}

/// For an OBJ written at `out` from a mesh with materials but no library: the library's name
/// beside it (`NAME.mtl`) and its text. `None` when the mesh needs none.
pub(crate) fn sidecar_library(materials: &Materials, out: &Path) -> Option<(PathBuf, String)> {
    if materials.list.is_empty() || !materials.libraries.is_empty() {
        return None;
    }
    let name = out.file_name()?.to_string_lossy();
    let stem = name
        .strip_suffix(".gz")
        .or_else(|| name.strip_suffix(".GZ"))
        .unwrap_or(&name);
    let stem = Path::new(stem).file_stem()?.to_string_lossy().into_owned();
    let file = format!("{stem}.mtl");
    Some((out.with_file_name(&file), mtl::write(&materials.list)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_climb_and_descend() {
        let r = relative(Path::new("/a/b/tex/x.png"), Path::new("/a/c/d"));
        assert_eq!(slashed(&r), "../../b/tex/x.png");
        assert_eq!(slashed(&normalized(Path::new("/a/./b/../c"))), "/a/c");
    }

    #[test]
    fn rebasing_reaches_the_same_file_from_the_new_folder() {
        let m = Materials {
            libraries: vec!["scan.mtl".into(), "/abs/lib.mtl".into()],
            list: vec![crate::mesh::Material {
                name: "skin".into(),
                texture: Some("tex/skin.png".into()),
            }],
            folder: Some(PathBuf::from("/data/scans")),
        };
        let r = rebased(&m, Path::new("/data/out/filtered/scan.obj"));
        assert_eq!(r.libraries, ["../../scans/scan.mtl", "/abs/lib.mtl"]);
        assert_eq!(
            r.list[0].texture.as_deref(),
            Some("../../scans/tex/skin.png")
        );
        assert_eq!(rebased(&m, Path::new("/data/scans/b.obj")), m);
    }

    #[test]
    fn anchoring_makes_relative_references_absolute_and_keeps_absolute_ones() {
        let m = Materials {
            libraries: vec!["../lib/scan.mtl".into(), "/abs/lib.mtl".into()],
            list: vec![crate::mesh::Material {
                name: "skin".into(),
                texture: Some("./tex/skin.png".into()),
            }],
            folder: Some(PathBuf::from("/data/scans")),
        };
        let a = anchored(&m);
        assert_eq!(a.libraries, ["/data/lib/scan.mtl", "/abs/lib.mtl"]);
        assert_eq!(
            a.list[0].texture.as_deref(),
            Some("/data/scans/tex/skin.png")
        );
        assert_eq!(a.folder, m.folder);
        let unread = Materials {
            folder: None,
            ..m.clone()
        };
        assert_eq!(anchored(&unread), unread);
    }
}
