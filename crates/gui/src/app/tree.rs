//! The plan tree: part, set-up, stiffness features, machining features and
//! operations, drawn lazily row by row and opened down to the selection.

use std::collections::BTreeSet;

use eframe::egui::{self, Color32, RichText};
use thinplan_plan::{Plan, StiffnessFeatureId};

use crate::relations;
use crate::state::Entity;

use super::ThinplanApp;

/// The height of one row: the lazy drawing and the scroll to the selection
/// both count rows by it.
const ROW_H: f32 = 18.0;

impl ThinplanApp {
    pub(super) fn tree(&mut self, ui: &mut egui::Ui) {
        let ThinplanApp {
            state,
            expanded,
            tree_scrolled_to,
            tree_cache,
            ..
        } = self;
        let Some(plan) = state.plan() else {
            ui.label("no part open");
            return;
        };
        open_path_to(plan, expanded, state.selection);
        let fresh =
            matches!(tree_cache, Some((g, e, _)) if *g == state.plan_generation && e == expanded);
        if !fresh {
            let rows = std::sync::Arc::new(tree_rows(plan, expanded));
            *tree_cache = Some((state.plan_generation, expanded.clone(), rows));
        }
        let rows = tree_cache.as_ref().map(|c| c.2.clone()).unwrap_or_default();
        let mut area = egui::ScrollArea::vertical().auto_shrink(false);
        if state.selection != *tree_scrolled_to {
            if let Some(i) = rows.iter().position(|r| Some(r.1) == state.selection) {
                let y = i as f32 * (ROW_H + ui.spacing().item_spacing.y) - 100.0;
                area = area.vertical_scroll_offset(y.max(0.0));
            }
            *tree_scrolled_to = state.selection;
        }
        let mut select = None;
        let mut toggle = None;
        area.show_rows(ui, ROW_H, rows.len(), |ui, range| {
            for &(depth, e, children) in &rows[range] {
                ui.horizontal(|ui| {
                    ui.add_space(depth as f32 * 14.0);
                    if children {
                        let open = expanded.contains(&e);
                        if ui.small_button(if open { "-" } else { "+" }).clicked() {
                            toggle = Some(e);
                        }
                    } else {
                        ui.add_space(18.0);
                    }
                    let mut text = RichText::new(relations::name(plan, e));
                    if state.changed.contains(&e) {
                        text = text.color(Color32::from_rgb(110, 220, 110));
                    }
                    if state.highlighted.contains(&e) {
                        text = text.color(Color32::from_rgb(90, 210, 255));
                    }
                    if ui
                        .selectable_label(state.selection == Some(e), text)
                        .clicked()
                    {
                        select = Some(e);
                    }
                });
            }
        });
        if let Some(e) = toggle {
            if !expanded.remove(&e) {
                expanded.insert(e);
            }
        }
        if let Some(e) = select {
            state.select(Some(e));
            *tree_scrolled_to = Some(e);
        }
    }
}

/// The tree's visible rows `(depth, entity, has children)`, shared.
pub(super) type TreeRows = std::sync::Arc<Vec<(usize, Entity, bool)>>;

/// Opens the tree's path down to the selection (coupling).
fn open_path_to(plan: &Plan, expanded: &mut BTreeSet<Entity>, selection: Option<Entity>) {
    if let Some(sel) = selection {
        let mut up = relations::owner(plan, sel);
        while let Some(o) = up {
            expanded.insert(o);
            up = relations::owner(plan, o);
        }
        if matches!(sel, Entity::Stiffness(_)) {
            expanded.insert(Entity::Part);
            expanded.insert(Entity::Setup);
        }
    }
}

/// The tree as a flat list of visible rows `(depth, entity, has children)`,
/// drawn lazily (only the rows in view), so ten thousand features cost what
/// a screenful does.
fn tree_rows(plan: &Plan, expanded: &BTreeSet<Entity>) -> Vec<(usize, Entity, bool)> {
    let mut rows = vec![(0, Entity::Part, true)];
    if !expanded.contains(&Entity::Part) {
        return rows;
    }
    rows.push((1, Entity::Setup, !plan.stiffness_features.is_empty()));
    if !expanded.contains(&Entity::Setup) {
        return rows;
    }
    let open_sf: BTreeSet<StiffnessFeatureId> = expanded
        .iter()
        .filter_map(|e| match e {
            Entity::Stiffness(id) => Some(*id),
            _ => None,
        })
        .collect();
    let has_mf: BTreeSet<StiffnessFeatureId> =
        plan.machining_features.iter().map(|m| m.owner).collect();
    let has_op: BTreeSet<thinplan_plan::MachiningFeatureId> =
        plan.operations.iter().map(|o| o.feature).collect();
    for f in &plan.stiffness_features {
        let e = Entity::Stiffness(f.id);
        rows.push((2, e, has_mf.contains(&f.id)));
        if !open_sf.contains(&f.id) {
            continue;
        }
        for m in plan.machining_features.iter().filter(|m| m.owner == f.id) {
            let me = Entity::Machining(m.id);
            rows.push((3, me, has_op.contains(&m.id)));
            if expanded.contains(&me) {
                for o in plan.operations.iter().filter(|o| o.feature == m.id) {
                    rows.push((4, Entity::Operation(o.id), false));
                }
            }
        }
    }
    rows
}
