//! The representation graph: which representations hold B-rep items,
//! and the parent-to-child links between them (representation
//! relationships and mapped items), checked for cycles.

use std::collections::{HashMap, HashSet};

use crate::p21::Value;
use crate::StepErrorKind;

use super::args::{place_of, A};
use super::shells::SOLID_TYPES;
use super::walk::Ctx;
use super::R;

/// How a child representation is placed in its parent.
#[derive(Clone, Copy)]
pub(super) enum Xf {
    Identity,
    /// Child-side placement (in child units), parent-side placement (in
    /// parent units): child → parent is `M(parent) · M(child)⁻¹`.
    Items {
        child: usize,
        parent: usize,
    },
}

#[derive(Clone, Copy)]
pub(super) struct Link {
    pub(super) child: usize,
    pub(super) xf: Xf,
    /// The entity that made the link (for error messages).
    via: usize,
}

/// Representations in file order, their contents, and the B-rep items they hold.
type RepTable = (Vec<usize>, HashMap<usize, RepInfo>, HashSet<usize>);

pub(super) struct RepInfo {
    pub(super) items: Vec<usize>,
    pub(super) context: Option<usize>,
    /// True when it has a solid, shell or surface model of its own.
    geometry: bool,
}

const REP_EXCLUDE: [&str; 3] = [
    "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION",
    "SHAPE_DEFINITION_REPRESENTATION",
    "DEFINITIONAL_REPRESENTATION",
];

impl<'x, 'a> Ctx<'x, 'a> {
    /// Items and context of a representation entity, if it is one.
    fn rep_args(&self, idx: usize) -> Option<A<'x, 'a>> {
        let h = self.head(idx);
        let a = if h.is_empty() {
            self.part_args(idx, "REPRESENTATION")?
        } else if (h.ends_with("SHAPE_REPRESENTATION") || h == "REPRESENTATION")
            && !REP_EXCLUDE.contains(&h)
        {
            self.args(idx)
        } else {
            return None;
        };
        (a.vals.len() == 3 && matches!(a.vals[1], Value::List(_))).then_some(a)
    }

    fn is_geometry_rep_type(&self, idx: usize) -> bool {
        matches!(
            self.head(idx),
            "ADVANCED_BREP_SHAPE_REPRESENTATION"
                | "MANIFOLD_SURFACE_SHAPE_REPRESENTATION"
                | "FACETED_BREP_SHAPE_REPRESENTATION"
                | "GEOMETRICALLY_BOUNDED_SURFACE_SHAPE_REPRESENTATION"
        )
    }
}

pub(super) fn build_reps<'x, 'a>(c: &mut Ctx<'x, 'a>) -> R<RepTable> {
    let n = c.ex.entities.len();
    let mut order = Vec::new();
    let mut reps = HashMap::new();
    let mut in_reps = HashSet::new();
    for idx in 0..n {
        let Some(a) = c.rep_args(idx) else { continue };
        let items = a.refs(1)?;
        let context = a.opt_r(2)?;
        let mut geometry = false;
        for &it in &items {
            let h = c.head(it);
            if SOLID_TYPES.contains(&h)
                || matches!(
                    h,
                    "SHELL_BASED_SURFACE_MODEL"
                        | "CLOSED_SHELL"
                        | "OPEN_SHELL"
                        | "ORIENTED_CLOSED_SHELL"
                        | "ORIENTED_OPEN_SHELL"
                )
            {
                geometry = true;
                in_reps.insert(it);
            }
        }
        order.push(idx);
        reps.insert(
            idx,
            RepInfo {
                items,
                context,
                geometry,
            },
        );
    }
    Ok((order, reps, in_reps))
}

/// Parent → children links between representations.
pub(super) fn build_links(
    c: &mut Ctx<'_, '_>,
    reps: &HashMap<usize, RepInfo>,
) -> R<HashMap<usize, Vec<Link>>> {
    let pd_reps = product_reps(c);
    let reversed = reversed_relationships(c, &pd_reps);
    let mut links: HashMap<usize, Vec<Link>> = HashMap::new();
    relationship_links(c, reps, &reversed, &mut links)?;
    mapped_item_links(c, reps, &mut links)?;
    Ok(links)
}

/// Product definition → its shape representations (for CDSR direction).
fn product_reps(c: &Ctx<'_, '_>) -> HashMap<usize, Vec<usize>> {
    let n = c.ex.entities.len();
    let mut pd_reps: HashMap<usize, Vec<usize>> = HashMap::new();
    for idx in 0..n {
        if c.head(idx) != "SHAPE_DEFINITION_REPRESENTATION" {
            continue;
        }
        let a = c.args(idx);
        let (Ok(Some(pds)), Ok(Some(rep))) = (a.opt_r(0), a.opt_r(1)) else {
            continue;
        };
        if let Ok(Some(pd)) = c.args(pds).opt_r(2) {
            pd_reps.entry(pd).or_default().push(rep);
        }
    }
    pd_reps
}

/// Relationship → reversed (rep_2 is the child).
fn reversed_relationships(
    c: &Ctx<'_, '_>,
    pd_reps: &HashMap<usize, Vec<usize>>,
) -> HashMap<usize, bool> {
    let n = c.ex.entities.len();
    let mut reversed: HashMap<usize, bool> = HashMap::new();
    for idx in 0..n {
        if c.head(idx) != "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION" {
            continue;
        }
        let a = c.args(idx);
        let (Ok(Some(rel)), Ok(Some(pds))) = (a.opt_r(0), a.opt_r(1)) else {
            continue;
        };
        let Ok(Some(nauo)) = c.args(pds).opt_r(2) else {
            continue;
        };
        let na = c.args(nauo);
        let (Ok(Some(parent_pd)), Ok(Some(child_pd))) = (na.opt_r(3), na.opt_r(4)) else {
            continue;
        };
        let Some((r1, r2)) = rel_reps(c, rel) else {
            continue;
        };
        let of = |pd: usize| pd_reps.get(&pd).map(|v| v.as_slice()).unwrap_or(&[]);
        let rev = of(child_pd).contains(&r2) || of(parent_pd).contains(&r1);
        reversed.insert(rel, rev);
    }
    reversed
}

/// Links made by representation relationships (with or without a
/// transformation), in file order.
fn relationship_links(
    c: &mut Ctx<'_, '_>,
    reps: &HashMap<usize, RepInfo>,
    reversed: &HashMap<usize, bool>,
    links: &mut HashMap<usize, Vec<Link>>,
) -> R<()> {
    let n = c.ex.entities.len();
    for idx in 0..n {
        if rel_reps(c, idx).is_some() {
            let a = rel_args(c, idx).ok_or_else(|| c.unsupported(idx, "relationship"))?;
            let rep1 = a.r(2)?;
            let rep2 = a.r(3)?;
            if !reps.contains_key(&rep1) || !reps.contains_key(&rep2) {
                continue;
            }
            let transformation = if let Some(t) =
                c.part_args(idx, "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION")
            {
                Some(t.r(0)?)
            } else if c.head(idx) == "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION" {
                Some(a.r(4)?)
            } else {
                None
            };
            let (child, parent, xf) = match transformation {
                Some(t) => {
                    let rev = reversed.get(&idx).copied().unwrap_or(false);
                    let (child, parent) = if rev { (rep2, rep1) } else { (rep1, rep2) };
                    let xf = if c.head(t) == "ITEM_DEFINED_TRANSFORMATION" {
                        let ta = c.args(t);
                        let (i1, i2) = (ta.r(2)?, ta.r(3)?);
                        if rev {
                            Xf::Items {
                                child: i2,
                                parent: i1,
                            }
                        } else {
                            Xf::Items {
                                child: i1,
                                parent: i2,
                            }
                        }
                    } else {
                        let label = c.type_label(t);
                        c.warn(
                            &format!("xf:{label}"),
                            format!("transformation kind {label} not supported; identity used"),
                        );
                        Xf::Identity
                    };
                    (child, parent, xf)
                }
                None => {
                    // A plain link between a shape representation and the one
                    // holding its geometry: the geometry side is the child.
                    let g1 = c.is_geometry_rep_type(rep1) || reps[&rep1].geometry;
                    let g2 = c.is_geometry_rep_type(rep2) || reps[&rep2].geometry;
                    if g1 && !g2 {
                        (rep1, rep2, Xf::Identity)
                    } else {
                        (rep2, rep1, Xf::Identity)
                    }
                }
            };
            links.entry(parent).or_default().push(Link {
                child,
                xf,
                via: idx,
            });
        }
    }
    Ok(())
}

/// Links made by mapped items, by representation in file order.
fn mapped_item_links(
    c: &Ctx<'_, '_>,
    reps: &HashMap<usize, RepInfo>,
    links: &mut HashMap<usize, Vec<Link>>,
) -> R<()> {
    let mut rep_ids: Vec<usize> = reps.keys().copied().collect();
    rep_ids.sort_unstable();
    for r in rep_ids {
        for &it in &reps[&r].items {
            if c.head(it) != "MAPPED_ITEM" {
                continue;
            }
            let a = c.args(it);
            let map = a.r(1)?;
            let target = a.r(2)?;
            let ma = c.expect_type(map, &["REPRESENTATION_MAP"], "a representation map")?;
            let origin = ma.r(0)?;
            let child = ma.r(1)?;
            if !reps.contains_key(&child) {
                return Err(ma.wrong("mapped representation is not a representation"));
            }
            links.entry(r).or_default().push(Link {
                child,
                xf: Xf::Items {
                    child: origin,
                    parent: target,
                },
                via: it,
            });
        }
    }
    Ok(())
}

fn rel_args<'x, 'a>(c: &Ctx<'x, 'a>, idx: usize) -> Option<A<'x, 'a>> {
    let h = c.head(idx);
    if h.is_empty() {
        c.part_args(idx, "REPRESENTATION_RELATIONSHIP")
    } else if h.ends_with("REPRESENTATION_RELATIONSHIP")
        || h == "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION"
    {
        Some(c.args(idx))
    } else {
        None
    }
}

fn rel_reps(c: &Ctx<'_, '_>, idx: usize) -> Option<(usize, usize)> {
    let a = rel_args(c, idx)?;
    Some((a.opt_r(2).ok()??, a.opt_r(3).ok()??))
}

/// Errors if the representation graph has a cycle (iterative DFS).
pub(super) fn check_acyclic(
    c: &Ctx<'_, '_>,
    order: &[usize],
    links: &HashMap<usize, Vec<Link>>,
) -> R<()> {
    // 0 unvisited, 1 on stack, 2 done
    let mut color: HashMap<usize, u8> = HashMap::new();
    for &root in order {
        if color.get(&root).copied().unwrap_or(0) != 0 {
            continue;
        }
        let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
        color.insert(root, 1);
        while let Some(&mut (node, ref mut next)) = stack.last_mut() {
            let kids = links.get(&node).map(|v| v.as_slice()).unwrap_or(&[]);
            if let Some(l) = kids.get(*next) {
                *next += 1;
                match color.get(&l.child).copied().unwrap_or(0) {
                    0 => {
                        color.insert(l.child, 1);
                        stack.push((l.child, 0));
                    }
                    1 => {
                        let id = |i: usize| c.ent(i).map(|e| e.id).unwrap_or(0);
                        let mut chain: Vec<String> = stack
                            .iter()
                            .skip_while(|(n, _)| *n != l.child)
                            .map(|(n, _)| format!("#{}", id(*n)))
                            .collect();
                        chain.push(format!("#{}", id(l.child)));
                        return Err(StepErrorKind::Cyclic {
                            place: place_of(c.ex, l.via),
                            chain: format!("assembly representations {}", chain.join(" -> ")),
                        });
                    }
                    _ => {}
                }
            } else {
                color.insert(node, 2);
                stack.pop();
            }
        }
    }
    Ok(())
}
