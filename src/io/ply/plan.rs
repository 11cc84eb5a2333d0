//! What the reader does with each property of an element, decided from the header.

use super::header::{ElementDef, PropKind};
use super::types::is_int;
use crate::io::{IoError, err_line};
use crate::mesh::{AttributeData, ListProperty, ScalarType};

/// What the reader does with one property of an element.
#[derive(Clone, Copy)]
pub(super) enum Plan {
    /// Scalar into a column; `finite` checks positions.
    Scalar { t: ScalarType, finite: bool },
    /// Face indices.
    Indices { count: ScalarType, item: ScalarType },
    /// Opaque list.
    List { count: ScalarType, item: ScalarType },
}

/// Output of one property.
pub(super) enum Out {
    Col(AttributeData),
    List(ListProperty),
    Indices,
}

/// Element kinds with a meaning for the mesh.
#[derive(PartialEq)]
pub(super) enum Role {
    Vertex,
    Face,
    Extra,
}

impl Role {
    /// The role of an element, by its name.
    pub(super) fn of(el: &ElementDef) -> Role {
        match el.name.as_str() {
            "vertex" => Role::Vertex,
            "face" => Role::Face,
            _ => Role::Extra,
        }
    }
}

pub(super) fn plan_element(el: &ElementDef, role: &Role) -> Result<Vec<Plan>, IoError> {
    let mut plans = Vec::with_capacity(el.props.len());
    let mut have_indices = false;
    for p in &el.props {
        let plan = match (p.kind, role) {
            (PropKind::Scalar(t), Role::Vertex) => Plan::Scalar {
                t,
                finite: matches!(p.name.as_str(), "x" | "y" | "z"),
            },
            (PropKind::Scalar(t), _) => Plan::Scalar { t, finite: false },
            (PropKind::List { count, item }, Role::Face)
                if !have_indices
                    && matches!(p.name.as_str(), "vertex_indices" | "vertex_index") =>
            {
                if !is_int(item) {
                    return Err(err_line(
                        el.line,
                        format!("face list {} must have an integer item type", p.name),
                    ));
                }
                have_indices = true;
                Plan::Indices { count, item }
            }
            (PropKind::List { count, item }, Role::Extra | Role::Face) => {
                Plan::List { count, item }
            }
            (PropKind::List { .. }, Role::Vertex) => {
                return Err(err_line(
                    el.line,
                    format!(
                        "list property {:?} on element {:?} is not supported",
                        p.name, el.name
                    ),
                ));
            }
        };
        plans.push(plan);
    }
    match role {
        Role::Vertex => {
            for c in ["x", "y", "z"] {
                if !el.props.iter().any(|p| p.name == c) {
                    return Err(err_line(el.line, format!("the vertex element has no {c}")));
                }
            }
        }
        Role::Face if !have_indices => {
            return Err(err_line(
                el.line,
                "the face element has no vertex_indices list",
            ));
        }
        _ => {}
    }
    Ok(plans)
}

/// Minimum bytes one row needs (binary: exact sizes; ASCII: one character and one separator
/// per value), used to reject absurd counts before allocating.
pub(super) fn min_row_bytes(plans: &[Plan], ascii: bool) -> u64 {
    plans
        .iter()
        .map(|p| match (p, ascii) {
            (_, true) => 2,
            (Plan::Scalar { t, .. }, false) => t.size() as u64,
            (Plan::Indices { count, .. } | Plan::List { count, .. }, false) => count.size() as u64,
        })
        .sum()
}
