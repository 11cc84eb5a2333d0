//! Checks on the files a command will write, made before the work so that a typo in `-o`
//! costs nothing and reads as an output problem, not as a problem with the input.

use std::path::Path;

/// Fails before any work when `path` cannot take a mesh: an extension no writer knows (with a
/// pointer to `meshpyr build` for `.pyr`), or a folder that is missing or not writable.
pub(crate) fn check_mesh_output(path: &Path) -> anyhow::Result<()> {
    check_not_directory(path)?;
    if has_extension(path, "pyr") {
        anyhow::bail!(
            "{}: this command writes meshes (.obj, .ply, .off, .stl, optionally .gz); \
             `meshpyr build IN -o {}` writes .pyr files",
            path.display(),
            path.display()
        );
    }
    meshpyr::io::MeshFormat::from_path(path)?;
    check_output_folder(path)
}

/// Writes `mesh` to `path` (atomically, references rebased), first warning about the texture
/// data the format cannot hold.
pub(crate) fn write_mesh_output(
    path: &Path,
    mesh: &meshpyr::mesh::PolygonMesh,
    opts: &meshpyr::io::WriteOptions,
) -> anyhow::Result<()> {
    let format = meshpyr::io::MeshFormat::from_path(path)?;
    if let Some(what) = meshpyr::io::texture_data_not_held(mesh, format) {
        eprintln!("warning: {}: {what}", path.display());
    }
    meshpyr::io::write_mesh_with(path, mesh, opts)?;
    Ok(())
}

/// Fails before any work when `path` is not a PNG name (the charts are PNG only, and PNG bytes
/// under another name would mislead every viewer), or when its folder cannot take it.
pub(crate) fn check_png_output(path: &Path) -> anyhow::Result<()> {
    if !has_extension(path, "png") {
        anyhow::bail!(
            "{}: charts are written as PNG only; name the output .png",
            path.display()
        );
    }
    check_output_folder(path)
}

/// Fails with "cannot write PATH: …" when `path` is a directory, or when its folder does not
/// exist, is not a directory or does not let us create a file (probed by creating and removing
/// an empty one, which is what the atomic write will do).
pub(crate) fn check_output_folder(path: &Path) -> anyhow::Result<()> {
    let cannot = |why: String| anyhow::anyhow!("cannot write {}: {why}", path.display());
    check_not_directory(path)?;
    let folder = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match std::fs::metadata(folder) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(cannot(format!(
                "the folder {} does not exist",
                folder.display()
            )));
        }
        Err(e) => return Err(cannot(format!("{}: {e}", folder.display()))),
        Ok(m) if !m.is_dir() => {
            return Err(cannot(format!("{} is not a folder", folder.display())));
        }
        Ok(_) => {}
    }
    let probe = folder.join(format!(".meshpyr-probe-{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        // Left over by a process with our id that died: the folder takes files.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(cannot(format!("{}: {e}", folder.display()))),
    }
}

/// Fails with "cannot write PATH: it is a directory" when it is one.
fn check_not_directory(path: &Path) -> anyhow::Result<()> {
    if path.is_dir() {
        anyhow::bail!("cannot write {}: it is a directory", path.display());
    }
    Ok(())
}

/// True when `path`'s extension is `ext` (case-insensitive).
fn has_extension(path: &Path, ext: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(ext))
}
