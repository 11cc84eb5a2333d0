//! The OBJ statements that apply to the faces after them: `usemtl`, `g`, `o`, `s`, and the
//! `mtllib` files that define the materials.

use std::collections::HashMap;

use crate::io::text;
use crate::io::{IoError, err_line};
use crate::mesh::corners::{
    GROUP_ATTRIBUTE, MATERIAL_ATTRIBUTE, OBJECT_ATTRIBUTE, SMOOTHING_ATTRIBUTE,
};
use crate::mesh::{Attribute, AttributeData, Material, PolygonMesh};

/// Which of the per-face values a statement sets.
#[derive(Clone, Copy)]
enum Slot {
    Material = 0,
    Group = 1,
    Object = 2,
    Smoothing = 3,
}

/// The face attribute each slot becomes.
const SLOT_NAMES: [&str; 4] = [
    MATERIAL_ATTRIBUTE,
    GROUP_ATTRIBUTE,
    OBJECT_ATTRIBUTE,
    SMOOTHING_ATTRIBUTE,
];

/// The values in force (−1: none; smoothing 0: off) and where they changed, as runs: most
/// files change material or group rarely, so a value per face would cost memory for nothing.
pub(super) struct FaceState {
    current: [i32; 4],
    /// `(first face, values)` whenever the values differ from the previous face's.
    runs: Vec<(u32, [i32; 4])>,
    /// Which slots some statement set.
    seen: [bool; 4],
    libraries: Vec<String>,
    /// Material, group and object names, in order of first use.
    tables: [NameTable; 3],
}

impl Default for FaceState {
    fn default() -> Self {
        FaceState {
            current: [-1, -1, -1, 0],
            runs: Vec::new(),
            seen: [false; 4],
            libraries: Vec::new(),
            tables: Default::default(),
        }
    }
}

impl FaceState {
    /// One `usemtl`, `mtllib`, `g`, `o` or `s` statement.
    pub(super) fn statement(
        &mut self,
        line: u64,
        kw: &[u8],
        args: &[&[u8]],
    ) -> Result<(), IoError> {
        let words = || -> Vec<String> {
            args.iter()
                .map(|a| String::from_utf8_lossy(a).into_owned())
                .collect()
        };
        match kw {
            b"mtllib" => self.libraries.extend(words()),
            b"usemtl" => self.set(Slot::Material, words().join(" ")),
            b"g" => self.set(Slot::Group, words().join(" ")),
            b"o" => self.set(Slot::Object, words().join(" ")),
            _ => self.set_smoothing(line, args)?,
        }
        Ok(())
    }

    /// Sets a named slot to the index of `name` (added on first use); no name is none (−1),
    /// which is how the writer says that faces after others have no material or group.
    fn set(&mut self, slot: Slot, name: String) {
        let i = match name.is_empty() {
            true => -1,
            false => self.tables[slot as usize].index_of(name),
        };
        self.current[slot as usize] = i;
        self.seen[slot as usize] = true;
    }

    /// `s <number>` or `s off`.
    fn set_smoothing(&mut self, line: u64, args: &[&[u8]]) -> Result<(), IoError> {
        let value = match args {
            [b"off"] => 0,
            [n] => text::parse_i64(n)
                .and_then(|n| i32::try_from(n).ok())
                .filter(|&n| n >= 0)
                .ok_or_else(|| err_line(line, format!("bad smoothing group {}", text::show(n))))?,
            _ => return Err(err_line(line, "an s line needs a number or off")),
        };
        self.current[Slot::Smoothing as usize] = value;
        self.seen[Slot::Smoothing as usize] = true;
        Ok(())
    }

    /// Face `f` is read: a new run starts when the values in force changed.
    #[inline]
    pub(super) fn face(&mut self, f: u32) {
        if self.seen != [false; 4] && self.runs.last().is_none_or(|r| r.1 != self.current) {
            self.runs.push((f, self.current));
        }
    }

    /// The face attributes of the slots some statement set, and the name tables.
    pub(super) fn finish(self, mesh: &mut PolygonMesh) {
        let nf = mesh.n_faces();
        for (k, name) in SLOT_NAMES.iter().enumerate() {
            if !self.seen[k] {
                continue;
            }
            let mut column = vec![if k == Slot::Smoothing as usize { 0 } else { -1 }; nf];
            for (r, &(first, values)) in self.runs.iter().enumerate() {
                let end = self.runs.get(r + 1).map_or(nf, |n| n.0 as usize);
                column[first as usize..end].fill(values[k]);
            }
            mesh.face_attributes.push(Attribute {
                name: (*name).into(),
                data: AttributeData::I32(column),
            });
        }
        let [materials, groups, objects] = self.tables;
        mesh.materials.libraries = self.libraries;
        mesh.materials.list = materials
            .names
            .into_iter()
            .map(|name| Material {
                name,
                texture: None,
            })
            .collect();
        mesh.group_names = groups.names;
        mesh.object_names = objects.names;
    }
}

/// Names in order of first use, with their indices.
#[derive(Default)]
struct NameTable {
    names: Vec<String>,
    index: HashMap<String, i32>,
}

impl NameTable {
    /// The index of `name`, appended when new.
    fn index_of(&mut self, name: String) -> i32 {
        let next = self.names.len() as i32;
        *self.index.entry(name).or_insert_with_key(|name| {
            self.names.push(name.clone());
            next
        })
    }
}
