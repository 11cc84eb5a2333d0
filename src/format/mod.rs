//! The `.pyr` file: the progressive hierarchy with its per-vertex details in a compact,
//! versioned, checksummed binary container (specified in `formats/pyr.md`).
//!
//! The codec reads and writes plain records of its own ([`PyrData`], [`PyramidOptions`],
//! [`StoredDetails`]) and knows nothing of the detail pyramid: turning a decoded file into a
//! [`Pyramid`](crate::pyramid::Pyramid), and a pyramid into the records it saves, lives in
//! [`crate::pyramid`].

pub mod container;
mod file;
pub(crate) mod pyr;
pub mod varint;

pub use file::PyrFile;
pub use pyr::{
    EncodedPyr, FileDetails, LevelMesh, PyrData, PyramidOptions, SizeReport, StoredDetails,
};
pub use pyr::{
    MAJOR, MINOR, MINOR_WITH_CORNERS, MINOR_WITHOUT_CORNERS, OLDEST_MAJOR, decode, encode,
    encode_sections, encode_with_details, read_level, read_level_within,
};
pub(crate) use pyr::{fix_checksums, fuzz_read_pyr, with_positions};
pub use pyr::{is_pyr, is_textured};

/// What can go wrong reading a `.pyr` file. Every variant says where.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FormatError {
    /// The file does not start with the `.pyr` signature.
    #[error("not a .pyr file (bad signature)")]
    NotPyr,
    /// The file ends before a field it announces.
    #[error("byte {offset}: file is truncated inside {what}")]
    Truncated {
        /// Offset where data ran out.
        offset: u64,
        /// What was being read.
        what: String,
    },
    /// A checksum does not match: the file is damaged.
    #[error("byte {offset}: checksum mismatch in {what} (the file is damaged)")]
    Checksum {
        /// What failed its check.
        what: String,
        /// Where it starts.
        offset: u64,
    },
    /// A field holds an impossible value.
    #[error("byte {offset}: {reason}")]
    Corrupt {
        /// Offset of the field.
        offset: u64,
        /// What is wrong.
        reason: String,
    },
    /// A version this reader does not understand.
    #[error("file version {major}.{minor} is newer than this meshpyr understands ({supported})")]
    Version {
        /// Major version in the file.
        major: u16,
        /// Minor version in the file.
        minor: u16,
        /// What this build reads.
        supported: String,
    },
}
