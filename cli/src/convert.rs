//! `meshpyr convert IN OUT`: any supported format to any other, data kept as it is.

use super::Global;
use meshpyr::io::{PlyEncoding, WriteOptions};
use meshpyr::wording::Count;
use std::path::PathBuf;

/// PLY encodings selectable on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(crate) enum PlyEncodingArg {
    /// Text.
    Ascii,
    /// Binary little endian (the default).
    BinaryLe,
    /// Binary big endian.
    BinaryBe,
}

/// Arguments of `meshpyr convert`.
#[derive(clap::Args, Debug)]
pub(crate) struct ConvertArgs {
    /// Input mesh (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub(crate) output: PathBuf,
    /// Encoding of PLY output.
    #[arg(long, value_enum, default_value = "binary-le")]
    pub(crate) ply_encoding: PlyEncodingArg,
    /// Write STL as text instead of binary.
    #[arg(long)]
    pub(crate) stl_ascii: bool,
}

/// Runs `meshpyr convert`.
pub(crate) fn run(args: ConvertArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let mesh = super::input::read_input_points(&args.input)?;
    let opts = WriteOptions {
        ply_encoding: match args.ply_encoding {
            PlyEncodingArg::Ascii => PlyEncoding::Ascii,
            PlyEncodingArg::BinaryLe => PlyEncoding::BinaryLittleEndian,
            PlyEncodingArg::BinaryBe => PlyEncoding::BinaryBigEndian,
        },
        stl_binary: !args.stl_ascii,
    };
    super::output::write_mesh_output(&args.output, &mesh, &opts)?;
    global.say(format_args!(
        "wrote {} ({}, {})",
        args.output.display(),
        Count(mesh.n_vertices(), "vertex", "vertices"),
        Count(mesh.n_faces(), "face", "faces")
    ));
    Ok(())
}
