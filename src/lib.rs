//! # meshpyr
//!
//! A multiresolution mesh editing engine built on a progressive-mesh hierarchy.
#![warn(missing_docs)]

pub mod io;
pub mod mesh;
