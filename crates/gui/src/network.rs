//! The network view of sequence constraints: a layered drawing
//! (longest-path layers, barycentre ordering) with simultaneous groups
//! drawn as one box, painted with egui's painter. The layout is computed
//! once per plan change; a frame only draws what is visible.

use std::collections::{BTreeMap, BTreeSet};

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, Vec2};
use thinplan_plan::{ConstraintKind, Plan};

use crate::relations;
use crate::state::{AppState, Entity};

/// Which constraints the view draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    Stiffness,
    Machining,
}

/// One box: a feature, or a simultaneous group of them.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub members: Vec<Entity>,
    pub layer: usize,
    /// Top-left corner in layout units.
    pub pos: Pos2,
    pub size: Vec2,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct Layout {
    pub nodes: Vec<Node>,
    /// Before edges between nodes (indices), deduplicated.
    pub edges: Vec<(usize, usize)>,
    pub node_of: BTreeMap<Entity, usize>,
    pub extent: Vec2,
}

pub const MEMBER_W: f32 = 64.0;
pub const NODE_H: f32 = 22.0;
const GAP_X: f32 = 14.0;
const GAP_Y: f32 = 46.0;
const WRAP: usize = 16;

/// Lays out the constraints of one level of the plan.
pub fn layout(plan: &Plan, level: Level) -> Layout {
    let (ents, cons): (Vec<Entity>, Vec<(Entity, Entity, ConstraintKind)>) = match level {
        Level::Stiffness => (
            plan.stiffness_features
                .iter()
                .map(|f| Entity::Stiffness(f.id))
                .collect(),
            plan.stiffness_constraints
                .iter()
                .map(|c| {
                    (
                        Entity::Stiffness(c.first),
                        Entity::Stiffness(c.second),
                        c.kind,
                    )
                })
                .collect(),
        ),
        Level::Machining => (
            plan.machining_features
                .iter()
                .map(|f| Entity::Machining(f.id))
                .collect(),
            plan.machining_constraints
                .iter()
                .map(|c| {
                    (
                        Entity::Machining(c.first),
                        Entity::Machining(c.second),
                        c.kind,
                    )
                })
                .collect(),
        ),
    };
    layout_graph(&ents, &cons)
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Lays out any constraint graph over `ents` (sorted ids make it deterministic).
pub fn layout_graph(ents: &[Entity], cons: &[(Entity, Entity, ConstraintKind)]) -> Layout {
    let index: BTreeMap<Entity, usize> = ents.iter().enumerate().map(|(i, e)| (*e, i)).collect();
    let mut parent: Vec<usize> = (0..ents.len()).collect();
    for (a, b, k) in cons {
        if let (ConstraintKind::Simultaneous, Some(&i), Some(&j)) = (k, index.get(a), index.get(b))
        {
            let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
            let (lo, hi) = (ri.min(rj), ri.max(rj));
            parent[hi] = lo;
        }
    }
    // Groups in order of their smallest member.
    let mut group_of_root: BTreeMap<usize, usize> = BTreeMap::new();
    let mut members: Vec<Vec<Entity>> = Vec::new();
    let mut group = vec![0; ents.len()];
    for i in 0..ents.len() {
        let r = find(&mut parent, i);
        let g = *group_of_root.entry(r).or_insert_with(|| {
            members.push(Vec::new());
            members.len() - 1
        });
        members[g].push(ents[i]);
        group[i] = g;
    }
    let n = members.len();
    let mut edges = BTreeSet::new();
    for (a, b, k) in cons {
        if let (ConstraintKind::Before, Some(&i), Some(&j)) = (k, index.get(a), index.get(b)) {
            if group[i] != group[j] {
                edges.insert((group[i], group[j]));
            }
        }
    }
    let edges: Vec<(usize, usize)> = edges.into_iter().collect();
    let mut succ = vec![Vec::new(); n];
    let mut pred = vec![Vec::new(); n];
    for &(a, b) in &edges {
        succ[a].push(b);
        pred[b].push(a);
    }
    // Longest-path layering by Kahn's order; nodes on a cycle (never in a
    // consistent plan) go one layer below the deepest.
    let mut indeg: Vec<usize> = pred.iter().map(Vec::len).collect();
    let mut layer = vec![usize::MAX; n];
    let mut ready: BTreeSet<usize> = (0..n).filter(|&i| indeg[i] == 0).collect();
    while let Some(&i) = ready.iter().next() {
        ready.remove(&i);
        let l = pred[i]
            .iter()
            .filter(|&&p| layer[p] != usize::MAX)
            .map(|&p| layer[p] + 1)
            .max()
            .unwrap_or(0);
        layer[i] = l;
        for &s in &succ[i] {
            indeg[s] -= 1;
            if indeg[s] == 0 {
                ready.insert(s);
            }
        }
    }
    let deepest = layer
        .iter()
        .filter(|l| **l != usize::MAX)
        .max()
        .copied()
        .unwrap_or(0);
    for l in layer.iter_mut().filter(|l| **l == usize::MAX) {
        *l = deepest + 1;
    }
    // Features with no constraint at all go in wrapped rows at the end, so
    // they do not stretch the first layer.
    let isolated: Vec<usize> = (0..n)
        .filter(|&i| pred[i].is_empty() && succ[i].is_empty())
        .collect();
    let connected_layers = (0..n)
        .filter(|&i| !(pred[i].is_empty() && succ[i].is_empty()))
        .map(|i| layer[i] + 1)
        .max()
        .unwrap_or(0);
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); connected_layers];
    for i in 0..n {
        if !(pred[i].is_empty() && succ[i].is_empty()) {
            rows[layer[i]].push(i);
        }
    }
    // Barycentre ordering: a few sweeps down and up.
    let mut rank = vec![0.0f32; n];
    let set_ranks = |rows: &Vec<Vec<usize>>, rank: &mut Vec<f32>| {
        for row in rows {
            for (k, &i) in row.iter().enumerate() {
                rank[i] = (k as f32 + 0.5) / row.len() as f32;
            }
        }
    };
    set_ranks(&rows, &mut rank);
    for sweep in 0..6 {
        let down = sweep % 2 == 0;
        let order: Vec<usize> = if down {
            (0..rows.len()).collect()
        } else {
            (0..rows.len()).rev().collect()
        };
        for l in order {
            let nb = if down { &pred } else { &succ };
            let mut keyed: Vec<(f32, usize)> = rows[l]
                .iter()
                .map(|&i| {
                    let ns = &nb[i];
                    let b = if ns.is_empty() {
                        rank[i]
                    } else {
                        ns.iter().map(|&j| rank[j]).sum::<f32>() / ns.len() as f32
                    };
                    (b, i)
                })
                .collect();
            keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            rows[l] = keyed.into_iter().map(|(_, i)| i).collect();
            let len = rows[l].len();
            for (k, &i) in rows[l].iter().enumerate() {
                rank[i] = (k as f32 + 0.5) / len as f32;
            }
        }
    }
    for chunk in isolated.chunks(WRAP) {
        rows.push(chunk.to_vec());
    }
    for (l, row) in rows.iter().enumerate() {
        for &i in row {
            layer[i] = l;
        }
    }
    let width = |g: usize| members[g].len() as f32 * MEMBER_W;
    let row_w: Vec<f32> = rows
        .iter()
        .map(|r| r.iter().map(|&g| width(g) + GAP_X).sum::<f32>())
        .collect();
    let max_w = row_w.iter().copied().fold(0.0, f32::max);
    let mut nodes: Vec<Option<Node>> = vec![None; n];
    for (l, row) in rows.iter().enumerate() {
        let mut x = (max_w - row_w[l]) * 0.5;
        for &g in row {
            nodes[g] = Some(Node {
                members: members[g].clone(),
                layer: l,
                pos: Pos2::new(x, l as f32 * (NODE_H + GAP_Y)),
                size: Vec2::new(width(g), NODE_H),
            });
            x += width(g) + GAP_X;
        }
    }
    let nodes: Vec<Node> = nodes.into_iter().flatten().collect();
    let mut node_of = BTreeMap::new();
    for (i, nd) in nodes.iter().enumerate() {
        for m in &nd.members {
            node_of.insert(*m, i);
        }
    }
    Layout {
        nodes,
        edges,
        node_of,
        extent: Vec2::new(max_w, rows.len() as f32 * (NODE_H + GAP_Y)),
    }
}

/// Below this node height on screen (px) the nodes are drawn as plain
/// quads in one mesh, without rounding, outlines, arrowheads or text: at
/// that size they are a few pixels and ten thousand of them would
/// otherwise cost more than the rest of the frame.
const LOD_NODE_PX: f32 = 8.0;

/// What decides the picture: when none of it changed since the last frame
/// the shapes drawn then are drawn again as they are.
#[derive(Debug, Clone, Copy, PartialEq)]
struct DrawKey {
    plan_generation: u64,
    style_generation: u64,
    level: Level,
    rect: Rect,
    zoom: f32,
    offset: Vec2,
    dark: bool,
}

/// The shapes of the last frame with the member boxes on screen (for
/// clicks and hover) and the entities drawn selected.
struct Drawn {
    key: DrawKey,
    shapes: Vec<egui::Shape>,
    hits: Vec<(Rect, Entity)>,
    selected: Vec<Entity>,
}

/// The view's own state: level, pan and zoom, and the layout cache.
pub struct NetworkView {
    pub level: Level,
    pub offset: Vec2,
    pub zoom: f32,
    cache: Option<(u64, Level, Layout)>,
    drawn: Option<Drawn>,
    /// The entities drawn as selected in the last frame (tests read it).
    pub drawn_selected: Vec<Entity>,
    /// How many frames reused the last frame's shapes (tests read it).
    pub reused: u64,
    fit_pending: bool,
}

impl Default for NetworkView {
    fn default() -> Self {
        NetworkView {
            level: Level::Stiffness,
            offset: Vec2::new(10.0, 10.0),
            zoom: 1.0,
            cache: None,
            drawn: None,
            drawn_selected: Vec::new(),
            reused: 0,
            fit_pending: true,
        }
    }
}

/// A straight band from `p` to `q`, `w` wide, as two triangles.
fn add_band(mesh: &mut egui::Mesh, p: Pos2, q: Pos2, w: f32, col: Color32) {
    let d = (q - p).normalized();
    let n = Vec2::new(-d.y, d.x) * (w * 0.5);
    let i = mesh.vertices.len() as u32;
    for v in [p + n, q + n, q - n, p - n] {
        mesh.colored_vertex(v, col);
    }
    mesh.add_triangle(i, i + 1, i + 2);
    mesh.add_triangle(i, i + 2, i + 3);
}

impl NetworkView {
    pub fn layout(&mut self, state: &AppState) -> &Layout {
        let stale = !matches!(&self.cache, Some((g, l, _)) if *g == state.plan_generation && *l == self.level);
        if stale {
            let lay = state
                .plan()
                .map(|p| layout(p, self.level))
                .unwrap_or_default();
            self.cache = Some((state.plan_generation, self.level, lay));
            self.fit_pending = true;
        }
        &self.cache.as_ref().expect("set above").2
    }

    pub fn ui(&mut self, ui: &mut egui::Ui, state: &mut AppState) {
        // The level follows the selection so both views show the same thing.
        match state.selection {
            Some(Entity::Stiffness(_)) => self.level = Level::Stiffness,
            Some(Entity::Machining(_)) => self.level = Level::Machining,
            _ => {}
        }
        ui.horizontal(|ui| {
            ui.label("Network:");
            ui.selectable_value(&mut self.level, Level::Stiffness, "stiffness constraints");
            ui.selectable_value(&mut self.level, Level::Machining, "machining constraints");
            if ui.button("Fit").clicked() {
                self.fit_pending = true;
            }
        });
        let (rect, resp) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, ui.visuals().extreme_bg_color);
        self.layout(state);
        let Some((_, _, lay)) = &self.cache else {
            return;
        };
        if self.fit_pending && lay.extent.x > 0.0 {
            let z = ((rect.width() - 20.0) / lay.extent.x)
                .min((rect.height() - 20.0) / lay.extent.y.max(1.0))
                .clamp(0.05, 1.5);
            self.zoom = z;
            self.offset = Vec2::new((rect.width() - lay.extent.x * z) * 0.5, 10.0);
            self.fit_pending = false;
        }
        if resp.dragged() {
            self.offset += resp.drag_delta();
        }
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let f = (scroll * 0.002).exp();
                if let Some(p) = resp.hover_pos() {
                    let local = p - rect.min;
                    self.offset = local - (local - self.offset) * f;
                }
                self.zoom = (self.zoom * f).clamp(0.02, 4.0);
            }
        }
        let Some(plan) = state.plan() else { return };
        let key = DrawKey {
            plan_generation: state.plan_generation,
            style_generation: state.style_generation,
            level: self.level,
            rect,
            zoom: self.zoom,
            offset: self.offset,
            dark: ui.visuals().dark_mode,
        };
        if self.drawn.as_ref().is_some_and(|d| d.key == key) {
            self.reused += 1;
        } else {
            self.drawn = Some(draw(ui, &painter, lay, plan, state, key));
        }
        let drawn = self.drawn.as_ref().expect("drawn above");
        painter.extend(drawn.shapes.iter().cloned());
        self.drawn_selected = drawn.selected.clone();
        let at = |p: Pos2| drawn.hits.iter().find(|(r, _)| r.contains(p)).map(|h| h.1);
        if let Some(e) = resp.hover_pos().and_then(at) {
            resp.clone().on_hover_text(relations::name(plan, e));
        }
        let clicked = if resp.clicked() {
            resp.interact_pointer_pos().and_then(at)
        } else {
            None
        };
        if let Some(e) = clicked {
            state.select(Some(e));
        } else if resp.clicked() {
            state.select(None);
        }
    }
}

/// The shapes of the visible part of the network for `key`.
fn draw(
    ui: &egui::Ui,
    painter: &egui::Painter,
    lay: &Layout,
    plan: &Plan,
    state: &AppState,
    key: DrawKey,
) -> Drawn {
    let DrawKey {
        rect, zoom, offset, ..
    } = key;
    let to_screen = |p: Pos2| rect.min + offset + p.to_vec2() * zoom;
    let selected = state.selection;
    // What the selection relates to, shown on the nodes as well.
    let related: BTreeSet<Entity> = match selected {
        Some(Entity::Stiffness(_)) | Some(Entity::Machining(_)) => state.highlighted.clone(),
        Some(e) => relations::owned(plan, e),
        None => BTreeSet::new(),
    };
    let visible = rect.expand(40.0);
    let edge_col = ui
        .visuals()
        .widgets
        .noninteractive
        .fg_stroke
        .color
        .gamma_multiply(0.6);
    let lod = NODE_H * zoom < LOD_NODE_PX;
    let mut shapes = Vec::new();
    let mut mesh = egui::Mesh::default();
    let mut hits = Vec::new();
    let mut drawn_selected = Vec::new();
    let hot_col = Color32::from_rgb(230, 140, 30);
    for &(a, b) in &lay.edges {
        let (na, nb) = (&lay.nodes[a], &lay.nodes[b]);
        let p = to_screen(na.pos + Vec2::new(na.size.x * 0.5, na.size.y));
        let q = to_screen(nb.pos + Vec2::new(nb.size.x * 0.5, 0.0));
        if !visible.intersects(Rect::from_two_pos(p, q)) {
            continue;
        }
        let hot = selected.is_some_and(|s| na.members.contains(&s) || nb.members.contains(&s));
        let stroke = if hot {
            Stroke::new(2.0, hot_col)
        } else {
            Stroke::new(1.0, edge_col)
        };
        if lod {
            add_band(&mut mesh, p, q, stroke.width, stroke.color);
            continue;
        }
        shapes.push(egui::Shape::line_segment([p, q], stroke));
        let dir = (q - p).normalized();
        let side = Vec2::new(-dir.y, dir.x) * 4.0;
        shapes.push(egui::Shape::convex_polygon(
            vec![q, q - dir * 8.0 + side, q - dir * 8.0 - side],
            stroke.color,
            Stroke::NONE,
        ));
    }
    let font = egui::FontId::proportional((11.0 * zoom).clamp(6.0, 16.0));
    let text_col = ui.visuals().strong_text_color();
    let group_col = Color32::from_rgb(140, 180, 230);
    for nd in &lay.nodes {
        let r = Rect::from_min_size(to_screen(nd.pos), nd.size * zoom);
        if !visible.intersects(r) {
            continue;
        }
        let group = nd.members.len() > 1;
        let fill = if group {
            Color32::from_rgb(70, 90, 120)
        } else {
            Color32::from_rgb(60, 70, 80)
        };
        if lod {
            if group {
                mesh.add_colored_rect(r.expand(1.0), group_col);
            }
            mesh.add_colored_rect(r, fill);
        } else {
            shapes.push(egui::epaint::RectShape::filled(r, 3.0, fill).into());
            if group {
                shapes.push(
                    egui::epaint::RectShape::stroke(
                        r,
                        3.0,
                        Stroke::new(1.5, group_col),
                        egui::StrokeKind::Outside,
                    )
                    .into(),
                );
            }
        }
        for (k, m) in nd.members.iter().enumerate() {
            let mr = Rect::from_min_size(
                r.min + Vec2::new(k as f32 * MEMBER_W * zoom, 0.0),
                Vec2::new(MEMBER_W * zoom, NODE_H * zoom),
            )
            .shrink(2.0 * zoom);
            hits.push((mr, *m));
            let (col, width) = if Some(*m) == selected {
                drawn_selected.push(*m);
                (Color32::from_rgb(255, 200, 40), 2.5)
            } else if related.contains(m) {
                (Color32::from_rgb(110, 210, 255), 2.0)
            } else if state.changed.contains(m) {
                (Color32::from_rgb(120, 220, 120), 1.5)
            } else {
                (Color32::TRANSPARENT, 0.0)
            };
            if width > 0.0 {
                if lod {
                    // A few pixels: the mark fills the member's box.
                    mesh.add_colored_rect(r.intersect(mr.expand(2.0 * zoom)), col);
                } else {
                    shapes.push(
                        egui::epaint::RectShape::stroke(
                            mr,
                            2.0,
                            Stroke::new(width, col),
                            egui::StrokeKind::Inside,
                        )
                        .into(),
                    );
                }
            }
            if !lod && zoom > 0.3 {
                let galley = painter.layout_no_wrap(m.to_string(), font.clone(), text_col);
                let tr = egui::Align2::CENTER_CENTER.anchor_size(mr.center(), galley.size());
                if !galley.is_empty() {
                    shapes.push(egui::Shape::galley(tr.min, galley, text_col));
                }
            }
        }
    }
    if !mesh.is_empty() {
        shapes.push(egui::Shape::mesh(mesh));
    }
    Drawn {
        key,
        shapes,
        hits,
        selected: drawn_selected,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use thinplan_plan::StiffnessFeatureId as S;

    fn e(i: u32) -> Entity {
        Entity::Stiffness(S(i))
    }

    #[test]
    fn layers_follow_longest_path_and_groups_are_one_node() {
        let ents: Vec<Entity> = (0..6).map(e).collect();
        let cons = vec![
            (e(0), e(1), ConstraintKind::Before),
            (e(1), e(2), ConstraintKind::Before),
            (e(0), e(2), ConstraintKind::Before),
            (e(2), e(3), ConstraintKind::Simultaneous),
        ];
        let lay = layout_graph(&ents, &cons);
        let layer = |x| lay.nodes[lay.node_of[&e(x)]].layer;
        assert_eq!((layer(0), layer(1), layer(2)), (0, 1, 2));
        assert_eq!(lay.node_of[&e(2)], lay.node_of[&e(3)]);
        assert_eq!(lay.nodes[lay.node_of[&e(2)]].members.len(), 2);
        // Unconstrained features sit in a row after the connected ones.
        assert!(layer(4) > layer(2) && layer(5) == layer(4));
        // Deterministic.
        assert_eq!(lay, layout_graph(&ents, &cons));
    }

    #[test]
    fn a_cycle_does_not_hang() {
        let ents: Vec<Entity> = (0..3).map(e).collect();
        let cons = vec![
            (e(0), e(1), ConstraintKind::Before),
            (e(1), e(0), ConstraintKind::Before),
            (e(1), e(2), ConstraintKind::Before),
        ];
        let lay = layout_graph(&ents, &cons);
        assert_eq!(lay.nodes.len(), 3);
    }
}
