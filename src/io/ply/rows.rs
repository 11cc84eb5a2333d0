//! The general body reader: one element's rows, value by value, from any source.

use super::header::ElementDef;
use super::plan::{Out, Plan};
use super::source::Source;
use super::types::empty_col;
use crate::io::IoError;
use crate::mesh::{AttributeData, ListProperty, ScalarType};

/// State shared by all elements while reading a body.
pub(super) struct Ctx {
    pub(super) nv: u64,
    pub(super) face_starts: Vec<u32>,
    pub(super) face_indices: Vec<u32>,
}

/// Reads `rows` rows of one element, value by value (all encodings, all layouts); `first` is
/// the element's row the first of them is, for messages (a streamed read decodes in chunks).
pub(super) fn read_rows(
    src: &mut dyn Source,
    el: &ElementDef,
    plans: &[Plan],
    (first, rows): (usize, usize),
    ctx: &mut Ctx,
) -> Result<Vec<Out>, IoError> {
    let mut outs = empty_outputs(el, plans, rows);
    let is_face = plans.iter().any(|p| matches!(p, Plan::Indices { .. }));
    if is_face {
        ctx.face_starts.reserve(rows + 1);
    }
    for local in 0..rows {
        let row = first + local;
        src.begin_row(&|| format!("{} {row} of {}", el.name, el.count))?;
        for (plan, out) in plans.iter().zip(outs.iter_mut()) {
            match (*plan, out) {
                (Plan::Scalar { finite, .. }, Out::Col(col)) => read_scalar(src, row, col, finite)?,
                (Plan::Indices { count, item }, Out::Indices) => {
                    read_face(src, row, count, item, ctx)?
                }
                (Plan::List { count, item }, Out::List(l)) => {
                    read_list(src, el, row, count, item, l)?
                }
                _ => unreachable!("plans and outputs are built together"),
            }
        }
        if is_face {
            check_corner_lists(src, (row, local), &outs, ctx)?;
        }
        src.end_row()?;
    }
    Ok(outs)
}

/// A face's per-corner list (`texcoord`, `corner_*`) holds a whole number of values per corner
/// (`texcoord`: two), or nothing for a face without them.
fn check_corner_lists(
    src: &dyn Source,
    (row, local): (usize, usize),
    outs: &[Out],
    ctx: &Ctx,
) -> Result<(), IoError> {
    let n = ctx.face_starts.len();
    let corners = (ctx.face_starts[n - 1] - ctx.face_starts[n - 2]) as usize;
    for out in outs {
        let Out::List(l) = out else { continue };
        let Some(per) = corner_list_width(&l.name) else {
            continue;
        };
        let len = (l.starts[local + 1] - l.starts[local]) as usize;
        let fits = match per {
            Some(k) => len == k * corners,
            None => corners > 0 && len.is_multiple_of(corners),
        };
        if len != 0 && !fits {
            let each = per.map_or("a whole number of".to_string(), |k| k.to_string());
            return Err(src.err(format!(
                "face {row}: list {:?} has {len} values for {corners} corners ({each} per corner)",
                l.name
            )));
        }
    }
    Ok(())
}

/// Whether a face list holds values per corner, and how many per corner when the name says:
/// `texcoord` two, `corner_normal` three, any other `corner_*` list as many as it holds.
pub(super) fn corner_list_width(name: &str) -> Option<Option<usize>> {
    match name {
        "texcoord" => Some(Some(2)),
        "corner_normal" => Some(Some(3)),
        n if n.starts_with("corner_") => Some(None),
        _ => None,
    }
}

/// One output per plan, with room for `rows` rows; lists carry their property's name.
fn empty_outputs(el: &ElementDef, plans: &[Plan], rows: usize) -> Vec<Out> {
    let mut outs: Vec<Out> = plans
        .iter()
        .map(|p| match *p {
            Plan::Scalar { t, .. } => Out::Col(empty_col(t, rows)),
            Plan::Indices { .. } => Out::Indices,
            Plan::List { count, item } => Out::List(ListProperty {
                name: String::new(),
                count_type: count,
                item_type: item,
                starts: {
                    let mut s = Vec::with_capacity(rows + 1);
                    s.push(0);
                    s
                },
                items: Vec::new(),
            }),
        })
        .collect();
    for (k, p) in el.props.iter().enumerate() {
        if let Out::List(l) = &mut outs[k] {
            l.name = p.name.clone();
        }
    }
    outs
}

/// Appends one scalar to `col`; a position (`finite`) must be finite.
#[inline]
fn read_scalar(
    src: &mut dyn Source,
    row: usize,
    col: &mut AttributeData,
    finite: bool,
) -> Result<(), IoError> {
    src.push_scalar(col)?;
    if finite {
        let x = col.get_f64(col.len() - 1);
        if !x.is_finite() {
            return Err(src.err(format!("vertex {row} has a non-finite coordinate")));
        }
    }
    Ok(())
}

/// Appends face `row`'s indices, each checked against the vertex count.
#[inline]
fn read_face(
    src: &mut dyn Source,
    row: usize,
    count: ScalarType,
    item: ScalarType,
    ctx: &mut Ctx,
) -> Result<(), IoError> {
    let n = src.int(count)?;
    if n < 0 {
        return Err(src.err(format!("face {row} has a negative length {n}")));
    }
    src.check_items(n as u64, item)?;
    for _ in 0..n {
        let i = src.int(item)?;
        if i < 0 {
            return Err(src.err(format!("face {row} has negative index {i}")));
        }
        if i as u64 >= ctx.nv {
            return Err(src.err(format!(
                "face {row} has index {i} but the file has {} vertices",
                ctx.nv
            )));
        }
        ctx.face_indices.push(i as u32);
    }
    let len = u32::try_from(ctx.face_indices.len())
        .map_err(|_| src.err("more than 2^32 - 1 face indices".into()))?;
    ctx.face_starts.push(len);
    Ok(())
}

/// Appends row `row` of an opaque list property.
#[inline]
fn read_list(
    src: &mut dyn Source,
    el: &ElementDef,
    row: usize,
    count: ScalarType,
    item: ScalarType,
    l: &mut ListProperty,
) -> Result<(), IoError> {
    let n = src.int(count)?;
    if n < 0 {
        return Err(src.err(format!(
            "{} {row}: list {:?} has a negative length {n}",
            el.name, l.name
        )));
    }
    src.check_items(n as u64, item)?;
    for _ in 0..n {
        l.items.push(src.num(item)?);
    }
    let len = u32::try_from(l.items.len())
        .map_err(|_| src.err("more than 2^32 - 1 list items".into()))?;
    l.starts.push(len);
    Ok(())
}
