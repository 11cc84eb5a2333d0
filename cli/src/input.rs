//! The input of the commands: a mesh file or a `.pyr` file (recognised by its signature,
//! whatever its name), read as a mesh or turned into a detail pyramid.

use super::blocks::PathOptions;
use super::{BarProgress, Global};
use anyhow::Context;
use meshpyr::format;
use meshpyr::io;
use meshpyr::memory::{self, InputSize, Job};
use meshpyr::mesh::{MissingSurface, PolygonMesh};
use meshpyr::pm::ProgressiveMesh;
use meshpyr::progress::{NoProgress, Progress};
use meshpyr::pyramid::{self, DetailSource, Pyramid, PyramidOptions, Staged};
use meshpyr::relax::{RelaxKind, RelaxationSpec};
use meshpyr::wording::Count;
use std::path::Path;
use std::time::Instant;

/// Reads the mesh a command works on: a mesh file, or a `.pyr` file (recognised by its
/// signature, whatever its name), whose stored input mesh is restored exactly — the file the
/// user built it from, so `info`, `convert`, `simplify`, `subdivide`, `smooth`, `compare` and
/// `build` take the file they keep as well.
///
/// Every command that takes this needs a surface: a file with nothing in it, a point cloud or
/// faces that all repeat a vertex is an error naming the file and what is missing
/// ([`read_input_points`] takes point clouds too).
pub(crate) fn read_input_mesh(path: &Path) -> anyhow::Result<PolygonMesh> {
    let mesh = read_any_input(path)?;
    require(path, mesh.check_surface())?;
    Ok(mesh)
}

/// [`read_input_mesh`] for a command that does `job` on the mesh: first refused in one line
/// when its estimated memory exceeds what the process may use ([`check_memory`]), before the
/// file is read; for a file whose counts were estimated from its size (OBJ, ASCII STL), again
/// with the counts read.
pub(crate) fn read_input_mesh_for(path: &Path, job: Job) -> anyhow::Result<PolygonMesh> {
    let estimated = check_memory(path, job)?;
    let mesh = read_input_mesh(path)?;
    if estimated {
        recheck_memory(path, job, &mesh)?;
    }
    Ok(mesh)
}

/// Refuses `job` on the input at `path` in one line when its estimated peak exceeds a hard
/// memory limit (`ulimit -v`, the cgroup's, the machine's RAM and swap), from the file's head
/// alone (see [`meshpyr::memory`]); warns when it exceeds the memory available now. Returns
/// whether the counts were only estimated from the file's size, so that the caller checks
/// again once it has read them ([`recheck_memory`]).
pub(crate) fn check_memory(path: &Path, job: Job) -> anyhow::Result<bool> {
    let Some(fit) = memory::check_file(path, job)? else {
        return Ok(false);
    };
    warn_short_of_available(path, job, &fit);
    Ok(fit.size.from_file_size)
}

/// [`check_memory`] with the counts of the mesh read from `path`.
fn recheck_memory(path: &Path, job: Job, mesh: &PolygonMesh) -> anyhow::Result<()> {
    let size = InputSize::mesh(mesh.n_vertices() as u64, mesh.n_faces() as u64);
    let fit = memory::check_size(path, job, &size)?;
    warn_short_of_available(path, job, &fit);
    Ok(())
}

/// A warning line when the job needs more than the memory available now (not an error:
/// other programs may end or be swapped out).
fn warn_short_of_available(path: &Path, job: Job, fit: &memory::Fit) {
    if let Some(available) = fit.short_of_available {
        eprintln!(
            "warning: {}: needs about {} of memory for {} vertices ({job}), {} available now; \
             it may swap or be stopped by the system",
            path.display(),
            memory::Bytes(fit.need.resident),
            fit.need.vertices,
            memory::Bytes(available),
        );
    }
}

/// [`read_input_mesh`] for the commands that take point clouds as well (`convert`): only a
/// file with nothing in it is an error.
pub(crate) fn read_input_points(path: &Path) -> anyhow::Result<PolygonMesh> {
    let mesh = read_any_input(path)?;
    require(path, mesh.check_not_empty())?;
    Ok(mesh)
}

fn read_any_input(path: &Path) -> anyhow::Result<PolygonMesh> {
    if is_pyr_file(path) {
        return Ok(load_pyr(path)?.input);
    }
    read_mesh_warning(path)
}

/// Reads a mesh file, with a warning on standard error for each file it names that is
/// missing (material libraries, images, undefined materials).
pub(crate) fn read_mesh_warning(path: &Path) -> anyhow::Result<PolygonMesh> {
    let (mesh, warnings) = io::read_mesh_reporting(path)?;
    for w in warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok(mesh)
}

/// A warning on standard error when `output`, made with new faces, lacks the per-corner
/// data, materials, groups or face properties that `input` has.
pub(crate) fn warn_face_data_dropped(path: &Path, input: &PolygonMesh, output: &PolygonMesh) {
    if output.face_data_dropped().is_none()
        && let Some(what) = input.face_data_dropped()
    {
        eprintln!("warning: {}: {what}", path.display());
    }
}

/// A failed content check as an error naming the file.
pub(crate) fn require(path: &Path, check: Result<(), MissingSurface>) -> anyhow::Result<()> {
    check.map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// True when `path` is a `.pyr` file (by its signature; an unreadable file is "not").
pub(crate) fn is_pyr_file(path: &Path) -> bool {
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok_and(|_| format::is_pyr(&head))
}

/// Decodes a whole `.pyr` file in place (validated), errors naming the file.
pub(crate) fn load_pyr(path: &Path) -> anyhow::Result<format::PyrData> {
    let file =
        format::PyrFile::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    file.decode()
        .with_context(|| format!("cannot load {}", path.display()))
}

/// Decodes the bytes of the `.pyr` file `path` (validated), errors naming the file.
pub(crate) fn decode_pyr(path: &Path, bytes: &[u8]) -> anyhow::Result<format::PyrData> {
    format::decode(bytes).with_context(|| format!("cannot load {}", path.display()))
}

/// Reads `path` and builds its progressive mesh and pyramid, reporting progress and timing
/// (the pyramid's options say which relaxation it was analysed with). `relax` defaults to the
/// second-difference operator. A `.pyr` file (detected by its signature) is loaded instead,
/// with the relaxation recorded in it unless `relax` asks for another, and with its stored
/// details when they were analysed with that relaxation (else they are recomputed, and the
/// message says why).
pub(crate) fn load_pyramid(
    path: &Path,
    relax: Option<RelaxKind>,
    global: &Global,
) -> anyhow::Result<Pyramid> {
    load_pyramid_by(path, None, relax, &PathOptions::default(), global)
}

/// [`load_pyramid`], a mesh input's hierarchy built on the path `options` choose (said
/// unless `--quiet`; a `.pyr` file's hierarchy is read, not built) for a command writing
/// `output` (where a path chosen by memory puts its task files).
pub(crate) fn load_pyramid_by(
    path: &Path,
    output: Option<&Path>,
    relax: Option<RelaxKind>,
    options: &PathOptions,
    global: &Global,
) -> anyhow::Result<Pyramid> {
    let wanted = relax.map(RelaxKind::spec);
    if is_pyr_file(path) {
        options.apply_allowance();
        check_memory(path, Job::Pyramid)?;
        return load_pyr_scan(path, wanted, global);
    }
    let input = read_input_mesh_for(path, Job::Pyramid)?;
    let options = PyramidOptions {
        relaxation: wanted.unwrap_or_default(),
        pm: options.pm_options(path, output, Job::Pyramid, &input, global)?,
    };
    let name = path.display().to_string();
    build_pyramid_with(input, &options, &name, global, &NoProgress, &mut |_| {})
}

/// Loads a `.pyr` file and its pyramid (with `relaxation`, default the file's), from its
/// stored details when they fit, and says which path it took.
fn load_pyr_scan(
    path: &Path,
    relaxation: Option<RelaxationSpec>,
    global: &Global,
) -> anyhow::Result<Pyramid> {
    let start = Instant::now();
    let data = load_pyr(path)?;
    pyramid_of_pyr(path, data, relaxation, start, global, &NoProgress)
}

/// The pyramid of the `.pyr` file `path`, opened as `file` (with its relaxation and stored
/// details), in two stages when the file allows ([`Staged`]): the pyramid of the levels up
/// to `level_of(hierarchy)` from the stored details, and what records the rest. Progress also
/// goes to `also`; the file is closed once decoded.
pub(crate) fn staged_pyramid_of_pyr_file(
    path: &Path,
    file: format::PyrFile,
    level_of: &dyn Fn(&ProgressiveMesh) -> usize,
    global: &Global,
    also: &dyn Progress,
) -> anyhow::Result<Staged> {
    let start = Instant::now();
    let data = file
        .decode()
        .with_context(|| format!("cannot load {}", path.display()))?;
    drop(file);
    let level = level_of(&data.pm);
    let loaded = start.elapsed().as_secs_f64();
    let bar = global.progress("analysis");
    let staged = data
        .into_pyramid_staged(level, &Both(&BarProgress(&bar), also))
        .with_context(|| format!("cannot analyse {}", path.display()))?;
    bar.finish_and_clear();
    let took = start.elapsed().as_secs_f64() - loaded;
    match &staged {
        Staged::Whole(scan, from) => say_loaded(path, scan, from, loaded, took, global),
        Staged::Prefix(s) => global.say(format_args!(
            "{}: {} vertices, levels {}..={} (loaded in {loaded:.2} s, stored details, weights              and fans up to level {} computed in {took:.2} s, the rest in the background){}",
            path.display(),
            s.scan.input.n_vertices(),
            s.scan.pm.n_base_vertices(),
            s.scan.pm.n_vertices(),
            s.scan.pyramid.n_vertices(),
            extra_vertices_note(s.scan.input.n_vertices(), s.scan.pm.n_vertices()),
        )),
    }
    Ok(staged)
}

/// The pyramid of a loaded `.pyr` file (`start`: when loading began), saying which path it
/// took: the stored details, or the analysis and why. Progress goes to a bar and to `also`.
fn pyramid_of_pyr(
    path: &Path,
    data: format::PyrData,
    relaxation: Option<RelaxationSpec>,
    start: Instant,
    global: &Global,
    also: &dyn Progress,
) -> anyhow::Result<Pyramid> {
    let loaded = start.elapsed().as_secs_f64();
    let bar = global.progress("analysis");
    let (scan, from) = data
        .into_pyramid_with(relaxation, &Both(&BarProgress(&bar), also))
        .with_context(|| format!("cannot analyse {}", path.display()))?;
    bar.finish_and_clear();
    let took = start.elapsed().as_secs_f64() - loaded;
    say_loaded(path, &scan, &from, loaded, took, global);
    Ok(scan)
}

/// Says which path loading `path` took (`loaded`: seconds to decode, `took`: to make the
/// pyramid).
fn say_loaded(
    path: &Path,
    scan: &Pyramid,
    from: &DetailSource,
    loaded: f64,
    took: f64,
    global: &Global,
) {
    let p = &scan.pyramid;
    let path_taken = match from {
        DetailSource::Stored => format!("stored details, weights and fans computed in {took:.2} s"),
        // A file without details says what it always said.
        DetailSource::Recomputed(why) if why == pyramid::NO_STORED_DETAILS => {
            format!("details recomputed in {took:.2} s")
        }
        DetailSource::Recomputed(why) => format!("details recomputed in {took:.2} s: {why}"),
    };
    global.say(format_args!(
        "{}: {} vertices, levels {}..={} (loaded in {:.2} s, {path_taken}){}",
        path.display(),
        scan.input.n_vertices(),
        p.n_base_vertices(),
        p.n_vertices(),
        loaded,
        extra_vertices_note(scan.input.n_vertices(), p.n_vertices()),
    ));
}

/// The detail spectrum of `path` (relaxation `relax`, default the file's or
/// second-difference): a `.pyr` file with usable stored details gives it without any
/// analysis, and says so; anything else goes through [`load_pyramid`].
pub(crate) fn load_spectrum(
    path: &Path,
    relax: Option<RelaxKind>,
    global: &Global,
) -> anyhow::Result<meshpyr::pyramid::Spectrum> {
    if !is_pyr_file(path) {
        return Ok(load_pyramid(path, relax, global)?.spectrum());
    }
    let relaxation = relax.map(RelaxKind::spec);
    check_memory(path, Job::Pyramid)?;
    let start = Instant::now();
    let data = load_pyr(path)?;
    let Ok(spectrum) = data.stored_spectrum(relaxation) else {
        return Ok(pyramid_of_pyr(path, data, relaxation, start, global, &NoProgress)?.spectrum());
    };
    global.say(format_args!(
        "{}: {} vertices, levels {}..={} (loaded with its stored details in {:.2} s, no analysis){}",
        path.display(),
        data.input.n_vertices(),
        data.pm.n_base_vertices(),
        data.pm.n_vertices(),
        start.elapsed().as_secs_f64(),
        extra_vertices_note(data.input.n_vertices(), data.pm.n_vertices()),
    ));
    Ok(spectrum)
}

/// Builds the pyramid of an already-read mesh; `name` is used in messages.
pub(crate) fn build_pyramid(
    input: PolygonMesh,
    relaxation: RelaxationSpec,
    name: &str,
    global: &Global,
) -> anyhow::Result<Pyramid> {
    build_pyramid_watched(input, relaxation, name, global, &NoProgress, &mut |_| {})
}

/// [`build_pyramid`], its progress also reported to `also` and its progressive mesh handed to
/// `hierarchy_built` before the analysis (the editor shows it while the scan opens).
pub(crate) fn build_pyramid_watched(
    input: PolygonMesh,
    relaxation: RelaxationSpec,
    name: &str,
    global: &Global,
    also: &dyn Progress,
    hierarchy_built: &mut dyn FnMut(&ProgressiveMesh),
) -> anyhow::Result<Pyramid> {
    let options = PyramidOptions {
        relaxation,
        ..PyramidOptions::default()
    };
    build_pyramid_with(input, &options, name, global, also, hierarchy_built)
}

/// [`build_pyramid_watched`] with all the build options.
fn build_pyramid_with(
    input: PolygonMesh,
    options: &PyramidOptions,
    name: &str,
    global: &Global,
    also: &dyn Progress,
    hierarchy_built: &mut dyn FnMut(&ProgressiveMesh),
) -> anyhow::Result<Pyramid> {
    let start = Instant::now();
    let bar = global.progress("pyramid");
    let progress = Both(&BarProgress(&bar), also);
    let scan = Pyramid::build_staged(input, options, &progress, hierarchy_built)
        .with_context(|| format!("cannot build the detail pyramid of {name}"))?;
    bar.finish_and_clear();
    say_first_pieces(name, &scan.pm, global);
    let p = &scan.pyramid;
    global.say(format_args!(
        "{name}: {} vertices, levels {}..={}, {} details ({} relaxation) in {:.2} s{}",
        scan.input.positions.len(),
        p.n_base_vertices(),
        p.n_vertices(),
        p.n_details(),
        p.relaxation(),
        start.elapsed().as_secs_f64(),
        extra_vertices_note(scan.input.n_vertices(), p.n_vertices()),
    ));
    Ok(scan)
}

/// Says how a partitioned build through files made its first pieces (nothing for another
/// build).
pub(crate) fn say_first_pieces(name: &str, pm: &ProgressiveMesh, global: &Global) {
    if let Some(first) = pm.first_pieces() {
        global.say(format_args!("{name}: {first}"));
    }
}

/// Progress shown in two places.
struct Both<'a>(&'a dyn Progress, &'a dyn Progress);

impl Progress for Both<'_> {
    fn update(&self, fraction: f64) {
        self.0.update(fraction);
        self.1.update(fraction);
    }
}

/// Levels are vertex counts of the repaired mesh, so they can run past the file's vertex
/// count: says why when they do (empty otherwise).
pub(crate) fn extra_vertices_note(file_vertices: usize, finest: usize) -> String {
    if finest <= file_vertices {
        return String::new();
    }
    format!(
        "; levels above {file_vertices} count the {} the repair added at non-manifold spots \
         (see `meshpyr info`)",
        Count(finest - file_vertices, "vertex copy", "vertex copies")
    )
}
