//! The 3D viewport inside egui: camera (orbit, pan, zoom, fit), section
//! plane, object colours from the selection and the simulation, picking.
//! The scene is rebuilt only when the plan changes.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use eframe::egui::{self, Sense};
use eframe::egui_wgpu;
use glam::Vec3;
use thinplan_plan::{MachiningFeatureId, StiffnessKind};

use crate::relations;
use crate::render::{Uniforms, ViewportCallback};
use crate::scene::{Camera, Scene};
use crate::state::{AppState, Entity};

pub const SELECTED: [u8; 4] = [255, 205, 40, 210];
pub const RELATED: [u8; 4] = [90, 210, 255, 170];
const CHANGED: [u8; 4] = [110, 230, 110, 120];
const PART_SOLID: [u8; 4] = [196, 200, 208, 255];
const PART_GHOST: [u8; 4] = [196, 200, 208, 50];
const BEING_CUT: [u8; 4] = [235, 60, 50, 220];
const SUPPORT: [u8; 4] = [80, 200, 120, 150];
const REMAINING: [u8; 4] = [90, 130, 220, 60];
const PATH: [u8; 4] = [255, 255, 255, 255];
const PATH_SELECTED: [u8; 4] = [255, 230, 0, 128];

/// Which simulation state each machining feature is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimState {
    Removed,
    BeingRemoved,
    /// Remaining stock of the wall being cut: what supports it.
    Support,
    Remaining,
}

/// The simulation's classification at `step` of `order`.
pub fn sim_states(
    plan: &thinplan_plan::Plan,
    order: &[MachiningFeatureId],
    step: usize,
) -> BTreeMap<MachiningFeatureId, SimState> {
    let owner = order
        .get(step)
        .and_then(|id| relations::mf(plan, *id))
        .map(|f| f.owner);
    order
        .iter()
        .enumerate()
        .map(|(i, id)| {
            let s = if i < step {
                SimState::Removed
            } else if i == step {
                SimState::BeingRemoved
            } else if relations::mf(plan, *id).map(|f| f.owner) == owner {
                SimState::Support
            } else {
                SimState::Remaining
            };
            (*id, s)
        })
        .collect()
}

fn kind_color(k: StiffnessKind) -> [u8; 4] {
    match k {
        StiffnessKind::Wall => [120, 150, 230, 45],
        StiffnessKind::Hole | StiffnessKind::Cutout | StiffnessKind::Slot => [200, 120, 230, 60],
        StiffnessKind::Pocket | StiffnessKind::Notch | StiffnessKind::Step => [230, 170, 90, 60],
        StiffnessKind::Chamfer | StiffnessKind::Fillet => [160, 160, 160, 50],
    }
}

pub struct Viewport {
    pub camera: Camera,
    scene: Arc<Scene>,
    style: Arc<Vec<[u8; 4]>>,
    style_key: (u64, u64, u32),
    pub show_stiffness: bool,
    pub show_machining: bool,
    pub show_paths: bool,
    pub part_solid: bool,
    pub section: bool,
    /// 0, 1, 2: the section plane's normal axis.
    pub section_axis: usize,
    /// 0..1 through the scene's box.
    pub section_at: f32,
    /// Whether the GPU side was installed (no wgpu: no 3D, the rest works).
    pub gpu: bool,
    fit_pending: bool,
}

impl Viewport {
    pub fn new(gpu: bool) -> Self {
        Viewport {
            camera: Camera::default(),
            scene: Arc::new(Scene::default()),
            style: Arc::new(Vec::new()),
            style_key: (0, 0, 0),
            show_stiffness: true,
            show_machining: true,
            show_paths: true,
            part_solid: false,
            section: false,
            section_axis: 0,
            section_at: 0.5,
            gpu,
            fit_pending: true,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Rebuilds the scene when the plan changed, the colours when the
    /// selection, simulation or display options did.
    pub fn sync(&mut self, state: &AppState) {
        // While a job runs the generation stays, so the B-rep is at hand
        // whenever the scene is rebuilt.
        if self.scene.generation != state.plan_generation {
            let first = self.scene.vertices.is_empty() && self.scene.lines.is_empty();
            self.scene = Arc::new(match state.plan() {
                Some(p) => Scene::build(p, state.session().map(|s| &s.brep), state.plan_generation),
                None => Scene {
                    generation: state.plan_generation,
                    ..Default::default()
                },
            });
            if first {
                self.fit_pending = true;
            }
        }
        let flags = u32::from(self.show_stiffness)
            | u32::from(self.show_machining) << 1
            | u32::from(self.show_paths) << 2
            | u32::from(self.part_solid) << 3;
        let key = (state.style_generation, state.plan_generation, flags);
        if key != self.style_key {
            self.style = Arc::new(self.compute_style(state));
            self.style_key = key;
        }
    }

    fn compute_style(&self, state: &AppState) -> Vec<[u8; 4]> {
        let Some(plan) = state.plan() else {
            return vec![[0; 4]; self.scene.objects.len()];
        };
        let sim = state.sim_step.map(|k| {
            let order = relations::machining_order(plan);
            sim_states(plan, &order, k)
        });
        let related: BTreeSet<Entity> = match state.selection {
            Some(e) if state.highlighted.is_empty() => relations::owned(plan, e),
            _ => state.highlighted.clone(),
        };
        self.scene
            .objects
            .iter()
            .map(|e| {
                let e = *e;
                if Some(e) == state.selection {
                    return SELECTED;
                }
                match e {
                    Entity::Part => {
                        if self.part_solid {
                            PART_SOLID
                        } else {
                            PART_GHOST
                        }
                    }
                    Entity::Setup => [0; 4],
                    Entity::Stiffness(id) => {
                        if related.contains(&e) {
                            RELATED
                        } else if !self.show_stiffness || sim.is_some() {
                            [0; 4]
                        } else if state.changed.contains(&e) {
                            CHANGED
                        } else {
                            relations::sf(plan, id).map_or([0; 4], |f| kind_color(f.kind))
                        }
                    }
                    Entity::Machining(id) => {
                        if let Some(sim) = &sim {
                            match sim.get(&id) {
                                Some(SimState::Removed) | None => [0; 4],
                                Some(SimState::BeingRemoved) => BEING_CUT,
                                Some(SimState::Support) => SUPPORT,
                                Some(SimState::Remaining) => REMAINING,
                            }
                        } else if related.contains(&e) {
                            RELATED
                        } else if !self.show_machining {
                            [0; 4]
                        } else if state.changed.contains(&e) {
                            CHANGED
                        } else {
                            REMAINING
                        }
                    }
                    Entity::Operation(_) => {
                        if !self.show_paths {
                            [0; 4]
                        } else if related.contains(&e) {
                            PATH_SELECTED
                        } else {
                            PATH
                        }
                    }
                }
            })
            .collect()
    }

    /// The entities drawn in the selection colour (tests read this).
    pub fn drawn_selected(&self) -> Vec<Entity> {
        self.scene
            .objects
            .iter()
            .zip(self.style.iter())
            .filter(|(_, c)| **c == SELECTED)
            .map(|(e, _)| *e)
            .collect()
    }

    pub fn fit(&mut self) {
        self.camera.fit(self.scene.min, self.scene.max);
    }

    pub fn ui(&mut self, ui: &mut egui::Ui, state: &mut AppState) {
        self.sync(state);
        ui.horizontal_wrapped(|ui| {
            ui.label("3D:");
            if ui.button("Fit").clicked() {
                self.fit_pending = true;
            }
            ui.checkbox(&mut self.part_solid, "solid part");
            ui.checkbox(&mut self.show_stiffness, "stiffness features");
            ui.checkbox(&mut self.show_machining, "machining features");
            ui.checkbox(&mut self.show_paths, "tool paths");
            ui.checkbox(&mut self.section, "section");
            if self.section {
                egui::ComboBox::from_id_salt("section axis")
                    .width(40.0)
                    .selected_text(["x", "y", "z"][self.section_axis.min(2)])
                    .show_ui(ui, |ui| {
                        for (i, n) in ["x", "y", "z"].iter().enumerate() {
                            ui.selectable_value(&mut self.section_axis, i, *n);
                        }
                    });
                ui.add(egui::Slider::new(&mut self.section_at, 0.0..=1.0).show_value(false));
            }
        });
        self.sync(state);
        if self.fit_pending {
            self.fit();
            self.fit_pending = false;
        }
        let (rect, resp) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        if resp.dragged_by(egui::PointerButton::Primary) && !ui.input(|i| i.modifiers.shift) {
            let d = resp.drag_delta();
            self.camera.orbit(d.x, d.y);
        }
        if resp.dragged_by(egui::PointerButton::Secondary)
            || resp.dragged_by(egui::PointerButton::Middle)
            || (resp.dragged_by(egui::PointerButton::Primary) && ui.input(|i| i.modifiers.shift))
        {
            let d = resp.drag_delta();
            self.camera.pan(d.x, d.y, rect.height());
        }
        if resp.hovered() {
            let s = ui.input(|i| i.smooth_scroll_delta.y);
            if s != 0.0 {
                self.camera.zoom((-s * 0.002).exp());
            }
        }
        if resp.double_clicked() {
            self.fit_pending = true;
        }
        let aspect = rect.width() / rect.height().max(1.0);
        if resp.clicked() {
            if let Some(p) = resp.interact_pointer_pos() {
                let nx = (p.x - rect.min.x) / rect.width() * 2.0 - 1.0;
                let ny = 1.0 - (p.y - rect.min.y) / rect.height() * 2.0;
                let (o, d) = self.camera.ray(nx, ny, aspect);
                let style = self.style.clone();
                let hit = self
                    .scene
                    .pick(o, d, |obj| style.get(obj).is_some_and(|c| c[3] > 0));
                state.select(hit.map(|o| self.scene.objects[o]));
            }
        }
        let (mn, mx) = (self.scene.min, self.scene.max);
        let axis = Vec3::AXES[self.section_axis.min(2)];
        let offset = mn.dot(axis) + (mx - mn).dot(axis) * self.section_at;
        let ppp = ui.ctx().pixels_per_point();
        let size_px = [
            (rect.width() * ppp).round().max(0.0) as u32,
            (rect.height() * ppp).round().max(0.0) as u32,
        ];
        let bg = ui.visuals().extreme_bg_color;
        let uniforms = Uniforms {
            view_proj: self.camera.view_proj(aspect).to_cols_array_2d(),
            light: (self.camera.eye() - self.camera.target + Vec3::Z * self.camera.distance * 0.5)
                .normalize_or(Vec3::Z)
                .extend(0.0)
                .to_array(),
            section: axis.extend(if self.section { 1.0 } else { 0.0 }).to_array(),
            flags: [offset, 0.0, 0.0, 0.0],
        };
        if self.gpu {
            ui.painter().add(egui_wgpu::Callback::new_paint_callback(
                rect,
                ViewportCallback {
                    scene: self.scene.clone(),
                    style: self.style.clone(),
                    style_generation: self.style_key.0
                        ^ (self.style_key.1 << 20)
                        ^ (u64::from(self.style_key.2) << 56),
                    uniforms,
                    size_px,
                    part_solid: self.part_solid,
                    background: [
                        bg.r() as f32 / 255.0,
                        bg.g() as f32 / 255.0,
                        bg.b() as f32 / 255.0,
                    ],
                },
            ));
        } else {
            ui.painter().rect_filled(rect, 0.0, bg);
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "no 3D: this build runs without wgpu",
                egui::FontId::proportional(14.0),
                ui.visuals().text_color(),
            );
        }
        if let Some(plan) = state.plan() {
            if let Some(e) = state.selection {
                ui.painter().text(
                    rect.left_top() + egui::vec2(6.0, 4.0),
                    egui::Align2::LEFT_TOP,
                    relations::name(plan, e),
                    egui::FontId::proportional(13.0),
                    egui::Color32::from_rgb(255, 205, 40),
                );
            }
        }
    }
}
