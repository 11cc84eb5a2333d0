//! Reading a PLY body into a mesh, element by element: plan the element's properties, check
//! that the rest of the file can hold its rows, decode them (a binary fast path when the
//! layout allows, else value by value) and store them where the element's role says.

use glam::DVec3;

use super::corners::lists_to_corners;
use super::fast::{float_positions, read_faces_fast, row_stride, scalar_columns};
use super::header::{ElementDef, Header};
use super::plan::{Out, Plan, Role, min_row_bytes, plan_element};
use super::rows::{Ctx, read_rows};
use super::source::{Ascii, Bin};
use crate::io::text::Lines;
use crate::io::{IoError, PlyEncoding, err_byte, err_line};
use crate::mesh::{
    Attribute, AttributeData, ElementProperty, ExtraElement, PolygonMesh, ScalarType,
};

/// The number of vertices, which face indices must stay below; it must fit in `u32`.
pub(super) fn vertex_count(header: &Header) -> Result<u64, IoError> {
    let Some(vertex_el) = header.elements.iter().find(|e| e.name == "vertex") else {
        return Err(err_line(
            header.body_line - 1,
            "the file has no vertex element",
        ));
    };
    let nv = vertex_el.count;
    if nv > u32::MAX as u64 {
        return Err(err_line(
            vertex_el.line,
            format!("{nv} vertices is more than 2^32 - 1"),
        ));
    }
    Ok(nv)
}

/// Where the reader stands in the body (both sources; the encoding says which one reads) and
/// the faces read so far.
pub(super) struct BodyReader<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) ascii: bool,
    pub(super) big: bool,
    pub(super) bin: Bin<'a>,
    pub(super) asc: Ascii<'a>,
    pub(super) ctx: Ctx,
}

/// One element's decoded properties in header order, and its positions when a fast path
/// decoded them straight from the bytes.
struct Decoded {
    outs: Vec<Out>,
    positions: Option<Vec<DVec3>>,
}

impl<'a> BodyReader<'a> {
    /// A reader at the start of the body `header` describes, for a file of `nv` vertices.
    pub(super) fn new(bytes: &'a [u8], header: &Header, nv: u64) -> Self {
        BodyReader {
            bytes,
            ascii: header.encoding == PlyEncoding::Ascii,
            big: header.encoding == PlyEncoding::BinaryBigEndian,
            bin: Bin {
                data: bytes,
                pos: header.body,
                last: header.body,
                big: header.encoding == PlyEncoding::BinaryBigEndian,
            },
            asc: Ascii {
                lines: Lines::new(&bytes[header.body.min(bytes.len())..], header.body_line),
                line_no: header.body_line - 1,
                toks: Vec::new(),
                next: 0,
            },
            ctx: Ctx {
                nv,
                face_starts: vec![0],
                face_indices: Vec::new(),
            },
        }
    }

    /// Reads the rows of `el` and stores them in `mesh` as the element's role says.
    pub(super) fn read_element(
        &mut self,
        el: &ElementDef,
        mesh: &mut PolygonMesh,
    ) -> Result<(), IoError> {
        let role = Role::of(el);
        let plans = plan_element(el, &role)?;
        if plans.is_empty() {
            mesh.extra_elements.push(empty_element(el)?);
            return Ok(());
        }
        let rows = self.check_room(el, &plans)?;
        let decoded = self.decode(el, &role, &plans, rows)?;
        match role {
            Role::Vertex => store_vertices(mesh, el, decoded),
            Role::Face => store_face_attributes(mesh, el, decoded.outs),
            Role::Extra => store_extra_element(mesh, el, rows, decoded.outs),
        }
        Ok(())
    }

    /// Hands the faces read to `mesh`, with their per-corner lists as corner attributes.
    pub(super) fn finish(self, mesh: &mut PolygonMesh) {
        mesh.face_starts = self.ctx.face_starts;
        mesh.face_indices = self.ctx.face_indices;
        lists_to_corners(mesh);
    }

    /// Rejects counts the rest of the file cannot hold, before allocating anything; returns
    /// the row count (which then fits in `usize`). Both readers, whole and streamed, refuse alike.
    pub(super) fn check_room(&self, el: &ElementDef, plans: &[Plan]) -> Result<usize, IoError> {
        let left = if self.ascii {
            // Rows are separated by line breaks; the last one may lack its own.
            self.asc.lines.rest_len() as u64 + 1
        } else {
            (self.bytes.len() - self.bin.pos) as u64
        };
        let need = el.count.saturating_mul(min_row_bytes(plans, self.ascii));
        if need > left {
            let what = format!(
                "element {:?} claims {} rows (at least {need} bytes) but only {left} bytes remain",
                el.name, el.count
            );
            return Err(if self.ascii {
                err_line(el.line, what)
            } else {
                err_byte(self.bin.pos as u64, what)
            });
        }
        Ok(el.count as usize) // fits: bounded by the file size above
    }

    /// Decodes the `rows` rows of `el`, by the fastest way its layout allows.
    fn decode(
        &mut self,
        el: &ElementDef,
        role: &Role,
        plans: &[Plan],
        rows: usize,
    ) -> Result<Decoded, IoError> {
        let all_scalar = plans.iter().all(|p| matches!(p, Plan::Scalar { .. }));
        if !self.ascii && all_scalar {
            return self.decode_scalar_block(el, role, plans, rows);
        }
        let outs = if let Some((count, item)) = self.fast_face_layout(plans) {
            self.bin.pos = read_faces_fast(
                self.bytes,
                self.bin.pos,
                (0, rows),
                count,
                item,
                &mut self.ctx,
            )?;
            vec![Out::Indices]
        } else if self.ascii {
            read_rows(&mut self.asc, el, plans, (0, rows), &mut self.ctx)?
        } else {
            read_rows(&mut self.bin, el, plans, (0, rows), &mut self.ctx)?
        };
        Ok(Decoded {
            outs,
            positions: None,
        })
    }

    /// A binary element of scalars only is a fixed-stride block: decoded column by column.
    fn decode_scalar_block(
        &mut self,
        el: &ElementDef,
        role: &Role,
        plans: &[Plan],
        rows: usize,
    ) -> Result<Decoded, IoError> {
        let stride = row_stride(plans);
        let start = self.bin.pos;
        let block = &self.bytes[start..start + rows * stride];
        // Common case: float x, y, z anywhere in the row, decoded in one pass.
        let positions = if *role == Role::Vertex {
            float_positions(el, block, stride, (start, 0), self.big)?
        } else {
            None
        };
        let outs = scalar_columns(
            plans,
            block,
            stride,
            (start, 0),
            self.big,
            positions.is_some(),
        )?;
        self.bin.pos += rows * stride;
        Ok(Decoded { outs, positions })
    }

    /// The count and item types when the element is only `vertex_indices` with 32-bit items
    /// in a little-endian body: the layout [`read_faces_fast`] decodes.
    fn fast_face_layout(&self, plans: &[Plan]) -> Option<(ScalarType, ScalarType)> {
        match *plans {
            [
                Plan::Indices {
                    count,
                    item: item @ (ScalarType::I32 | ScalarType::U32),
                },
            ] if !self.ascii && !self.big => Some((count, item)),
            _ => None,
        }
    }
}

/// An element without properties occupies no bytes; only its row count is kept.
fn empty_element(el: &ElementDef) -> Result<ExtraElement, IoError> {
    Ok(ExtraElement {
        name: el.name.clone(),
        rows: usize::try_from(el.count)
            .map_err(|_| err_line(el.line, format!("element count {} is too large", el.count)))?,
        properties: Vec::new(),
    })
}

/// x, y, z become the positions, every other property a vertex attribute.
fn store_vertices(mesh: &mut PolygonMesh, el: &ElementDef, decoded: Decoded) {
    let mut xyz: [Option<AttributeData>; 3] = [None, None, None];
    for (p, out) in el.props.iter().zip(decoded.outs) {
        let Out::Col(data) = out else { continue };
        match p.name.as_str() {
            "x" => xyz[0] = Some(data),
            "y" => xyz[1] = Some(data),
            "z" => xyz[2] = Some(data),
            _ => mesh.vertex_attributes.push(Attribute {
                name: p.name.clone(),
                data,
            }),
        }
    }
    let [Some(x), Some(y), Some(z)] = xyz else {
        unreachable!("checked by plan_element")
    };
    mesh.position_type = position_type(&x, &y, &z);
    mesh.positions = match decoded.positions {
        Some(p) => p,
        None => positions(&x, &y, &z),
    };
}

/// The scalar properties of `face` become face attributes and its lists face lists (the
/// indices are in the context; per-corner lists become corner attributes in `finish`).
fn store_face_attributes(mesh: &mut PolygonMesh, el: &ElementDef, outs: Vec<Out>) {
    for (p, out) in el.props.iter().zip(outs) {
        match out {
            Out::Col(data) => mesh.face_attributes.push(Attribute {
                name: p.name.clone(),
                data,
            }),
            Out::List(l) => mesh.face_lists.push(l),
            Out::Indices => {}
        }
    }
}

/// Any other element is kept verbatim.
fn store_extra_element(mesh: &mut PolygonMesh, el: &ElementDef, rows: usize, outs: Vec<Out>) {
    let properties = el
        .props
        .iter()
        .zip(outs)
        .map(|(p, out)| match out {
            Out::Col(data) => ElementProperty::Scalar(Attribute {
                name: p.name.clone(),
                data,
            }),
            Out::List(l) => ElementProperty::List(l),
            Out::Indices => unreachable!("extra elements have no indices"),
        })
        .collect();
    mesh.extra_elements.push(ExtraElement {
        name: el.name.clone(),
        rows,
        properties,
    });
}

/// The stored type of x, y, z when they agree; `None` for mixed types (the writer then picks
/// `float` or `double` by value, losslessly).
pub(super) fn position_type(
    x: &AttributeData,
    y: &AttributeData,
    z: &AttributeData,
) -> Option<ScalarType> {
    let (a, b, c) = (x.scalar_type(), y.scalar_type(), z.scalar_type());
    (a == b && b == c).then_some(a)
}

pub(super) fn positions(x: &AttributeData, y: &AttributeData, z: &AttributeData) -> Vec<DVec3> {
    match (x, y, z) {
        (AttributeData::F32(x), AttributeData::F32(y), AttributeData::F32(z)) => x
            .iter()
            .zip(y)
            .zip(z)
            .map(|((&x, &y), &z)| DVec3::new(x as f64, y as f64, z as f64))
            .collect(),
        (AttributeData::F64(x), AttributeData::F64(y), AttributeData::F64(z)) => x
            .iter()
            .zip(y)
            .zip(z)
            .map(|((&x, &y), &z)| DVec3::new(x, y, z))
            .collect(),
        _ => (0..x.len())
            .map(|i| DVec3::new(x.get_f64(i), y.get_f64(i), z.get_f64(i)))
            .collect(),
    }
}
