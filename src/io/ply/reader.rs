//! Reading a PLY body into a mesh.

use glam::DVec3;

use super::fast::{column, float_positions, read_faces_fast};
use super::header::parse_header;
use super::plan::{Out, Plan, Role, min_row_bytes, plan_element};
use super::rows::{Ctx, read_rows};
use super::source::{Ascii, Bin};
use super::types::empty_col;
use crate::io::text::Lines;
use crate::io::{IoError, PlyEncoding, err_byte, err_line};
use crate::mesh::{
    Attribute, AttributeData, ElementProperty, ExtraElement, PolygonMesh, ScalarType,
};

/// Reads a PLY file (any encoding).
pub fn read(bytes: &[u8]) -> Result<PolygonMesh, IoError> {
    let header = parse_header(bytes)?;
    let ascii = header.encoding == PlyEncoding::Ascii;
    let big = header.encoding == PlyEncoding::BinaryBigEndian;

    let roles: Vec<Role> = header
        .elements
        .iter()
        .map(|e| match e.name.as_str() {
            "vertex" => Role::Vertex,
            "face" => Role::Face,
            _ => Role::Extra,
        })
        .collect();
    let vertex_el = header.elements.iter().find(|e| e.name == "vertex");
    let nv = match vertex_el {
        Some(e) => e.count,
        None => {
            return Err(err_line(
                header.body_line - 1,
                "the file has no vertex element",
            ));
        }
    };
    if nv > u32::MAX as u64 {
        return Err(err_line(
            vertex_el.map_or(0, |e| e.line),
            format!("{nv} vertices is more than 2^32 - 1"),
        ));
    }

    let mut mesh = PolygonMesh::new();
    mesh.comments = header.comments;
    let mut ctx = Ctx {
        nv,
        face_starts: vec![0],
        face_indices: Vec::new(),
    };

    let mut bin = Bin {
        data: bytes,
        pos: header.body,
        last: header.body,
        big,
    };
    let mut asc = Ascii {
        lines: Lines::new(&bytes[header.body..], header.body_line),
        line_no: header.body_line - 1,
        toks: Vec::new(),
        next: 0,
    };

    for (el, role) in header.elements.iter().zip(&roles) {
        let plans = plan_element(el, role)?;
        if plans.is_empty() {
            // An element without properties occupies no bytes; only its row count is kept.
            mesh.extra_elements.push(ExtraElement {
                name: el.name.clone(),
                rows: usize::try_from(el.count).map_err(|_| {
                    err_line(el.line, format!("element count {} is too large", el.count))
                })?,
                properties: Vec::new(),
            });
            continue;
        }
        // Reject counts the rest of the file cannot hold, before allocating anything.
        let left = if ascii {
            // Rows are separated by line breaks; the last one may lack its own.
            asc.lines.rest_len() as u64 + 1
        } else {
            (bytes.len() - bin.pos) as u64
        };
        let need = el.count.saturating_mul(min_row_bytes(&plans, ascii));
        if need > left {
            let what = format!(
                "element {:?} claims {} rows (at least {need} bytes) but only {left} bytes remain",
                el.name, el.count
            );
            return Err(if ascii {
                err_line(el.line, what)
            } else {
                err_byte(bin.pos as u64, what)
            });
        }
        let rows = el.count as usize; // fits: bounded by the file size above

        let all_scalar = plans.iter().all(|p| matches!(p, Plan::Scalar { .. }));
        let mut direct_positions: Option<Vec<DVec3>> = None;
        let outs = if !ascii && all_scalar {
            // Fixed-stride block: decode column by column.
            let stride: usize = plans
                .iter()
                .map(|p| match p {
                    Plan::Scalar { t, .. } => t.size(),
                    _ => 0,
                })
                .sum();
            let block = &bytes[bin.pos..bin.pos + rows * stride];
            let start = bin.pos;
            // Common case: float x, y, z anywhere in the row, decoded in one pass.
            if *role == Role::Vertex {
                direct_positions = float_positions(el, block, stride, start, big)?;
            }
            let mut off = 0;
            let mut outs = Vec::with_capacity(plans.len());
            for plan in &plans {
                let Plan::Scalar { t, finite } = *plan else {
                    unreachable!()
                };
                if finite && direct_positions.is_some() {
                    outs.push(Out::Col(empty_col(t, 0)));
                    off += t.size();
                    continue;
                }
                let col = column(block, stride, off, t, big);
                let bad = match (&col, finite) {
                    (AttributeData::F32(v), true) => v.iter().position(|x| !x.is_finite()),
                    (AttributeData::F64(v), true) => v.iter().position(|x| !x.is_finite()),
                    _ => None, // integers are always finite
                };
                if let Some(i) = bad {
                    return Err(err_byte(
                        (start + i * stride + off) as u64,
                        format!("vertex {i} has a non-finite coordinate"),
                    ));
                }
                outs.push(Out::Col(col));
                off += t.size();
            }
            bin.pos += rows * stride;
            outs
        } else if !ascii
            && !big
            && plans.len() == 1
            && matches!(
                plans[0],
                Plan::Indices {
                    item: ScalarType::I32 | ScalarType::U32,
                    ..
                }
            )
        {
            let Plan::Indices { count, item } = plans[0] else {
                unreachable!()
            };
            bin.pos = read_faces_fast(bytes, bin.pos, rows, count, item, &mut ctx)?;
            vec![Out::Indices]
        } else if ascii {
            read_rows(&mut asc, el, &plans, rows, &mut ctx)?
        } else {
            read_rows(&mut bin, el, &plans, rows, &mut ctx)?
        };

        match role {
            Role::Vertex => {
                let mut xyz: [Option<AttributeData>; 3] = [None, None, None];
                for (p, out) in el.props.iter().zip(outs) {
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
                mesh.positions = match direct_positions.take() {
                    Some(p) => p,
                    None => positions(&x, &y, &z),
                };
            }
            Role::Face => {
                for (p, out) in el.props.iter().zip(outs) {
                    if let Out::Col(data) = out {
                        mesh.face_attributes.push(Attribute {
                            name: p.name.clone(),
                            data,
                        });
                    }
                }
            }
            Role::Extra => {
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
        }
    }
    mesh.face_starts = ctx.face_starts;
    mesh.face_indices = ctx.face_indices;
    Ok(mesh)
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
