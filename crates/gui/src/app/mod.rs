//! The eframe application: panels around the 3D viewport and the network
//! view, all reading one [`AppState`]; a click anywhere changes the one
//! selection every view shows.
//!
//! This module wires the panels to the state: the forms they share, the
//! application's construction, the keyboard shortcuts and the layout of
//! one frame. Each panel is a submodule.

mod actions;
mod drawing;
mod editor;
mod export;
mod files;
mod inspector;
mod setup;
mod simulation;
mod top_bar;
mod tree;

use std::collections::BTreeSet;

use eframe::egui::{self, RichText};
use thinplan_plan::{ConstraintKind, Region3, StiffnessFeatureId};

use crate::network::NetworkView;
use crate::state::{AppState, Entity};
use crate::viewport::Viewport;

pub use editor::ConnectAs;
pub use files::Picking;
use tree::TreeRows;

/// The text fields and choices of the panels (not part of the plan).
#[derive(Default)]
struct Forms {
    part_source: String,
    knowledge_dir: String,
    plan_path: String,
    up: String,
    machine: String,
    tool_set: String,
    material: String,
    thickness: f64,
    z_min: f64,
    z_max: f64,
    spindle: f64,
    /// Machining-feature edits: split height, split line (x1, y1, x2, y2
    /// in the feature's profile coordinates), the feature to merge with.
    split_z: f64,
    split_line: [f64; 4],
    merge_with: Option<thinplan_plan::MachiningFeatureId>,
    /// A profile being drawn (`x, y; …` in the set-up's plan view) and its
    /// z range along up.
    draw_text: String,
    draw_z: (f64, f64),
    /// Export: post-processor id and the two files.
    post: String,
    gcode_path: String,
    sheet_path: String,
    /// For which selection the numbers above were filled in.
    filled_for: Option<(Entity, u64)>,
    other: Option<StiffnessFeatureId>,
    kind: Option<ConstraintKind>,
    /// A connection to add: the other feature and how the selected one
    /// stands to it.
    connect_to: Option<StiffnessFeatureId>,
    connect_as: ConnectAs,
    /// The feed (mm/min) of each kind of move of the selected operation.
    feeds: Vec<(Region3, f64)>,
    /// Its lowest and highest feed per kind, found once per plan change
    /// (an operation may have a million moves; not walked every frame).
    feed_ranges: Vec<(Region3, f64, f64)>,
}

pub struct ThinplanApp {
    pub state: AppState,
    pub viewport: Viewport,
    pub network: NetworkView,
    forms: Forms,
    /// Tree nodes the user opened.
    expanded: BTreeSet<Entity>,
    /// The selection the tree last scrolled to.
    tree_scrolled_to: Option<Entity>,
    /// The tree's rows for (plan generation, opened nodes): rebuilt only
    /// when either changes, not every frame (ten thousand features).
    tree_cache: Option<(u64, BTreeSet<Entity>, TreeRows)>,
    /// Simulation on/off and position (kept when the plan changes if it fits).
    pub simulate: bool,
    pub sim_index: usize,
    /// The in-window file picker (egui_file) while it is open, and what it
    /// was opened for.
    pub file_dialog: Option<(Picking, egui_file::FileDialog)>,
}

impl ThinplanApp {
    /// The application opening `source` (a part file or `builtin:NAME`).
    pub fn new(cc: &eframe::CreationContext<'_>, source: &str) -> Self {
        let gpu = match &cc.wgpu_render_state {
            Some(rs) => {
                crate::render::install(rs);
                true
            }
            None => false,
        };
        Self::with_state(AppState::open_default(source), gpu)
    }

    /// The application on a prepared state (benchmarks, tests).
    pub fn from_state(cc: &eframe::CreationContext<'_>, state: AppState) -> Self {
        let gpu = match &cc.wgpu_render_state {
            Some(rs) => {
                crate::render::install(rs);
                true
            }
            None => false,
        };
        Self::with_state(state, gpu)
    }

    pub fn with_state(state: AppState, gpu: bool) -> Self {
        let mut app = ThinplanApp {
            state,
            viewport: Viewport::new(gpu),
            network: NetworkView::default(),
            forms: Forms::default(),
            expanded: BTreeSet::from([Entity::Part, Entity::Setup]),
            tree_scrolled_to: None,
            tree_cache: None,
            simulate: false,
            sim_index: 0,
            file_dialog: None,
        };
        app.fill_forms_from_plan();
        app
    }

    fn fill_forms_from_plan(&mut self) {
        if let Some(p) = self.state.plan() {
            self.forms.part_source = p.part.source.clone();
            self.forms.up = format!("{}, {}, {}", p.setup.up.x, p.setup.up.y, p.setup.up.z);
            self.forms.machine = p.setup.machine.clone();
            self.forms.tool_set = p.setup.tool_set.clone();
            self.forms.material = p.setup.material.clone();
        }
    }

    /// Everything but drawing: job polling and keyboard shortcuts.
    fn tick(&mut self, ctx: &egui::Context) {
        if self.state.poll_job() {
            self.fill_forms_from_plan();
        }
        if self.state.is_running() {
            ctx.request_repaint_after(std::time::Duration::from_millis(50));
        }
        let (undo, redo) = ctx.input_mut(|i| {
            let redo = i.consume_key(
                egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
                egui::Key::Z,
            ) || i.consume_key(egui::Modifiers::COMMAND, egui::Key::Y);
            let undo = i.consume_key(egui::Modifiers::COMMAND, egui::Key::Z);
            (undo, redo)
        });
        if undo {
            self.state.undo();
        }
        if redo {
            self.state.redo();
        }
        // The simulation follows the slider.
        let n = self.state.plan().map_or(0, |p| p.machining_features.len());
        let step = (self.simulate && n > 0).then(|| self.sim_index.min(n - 1));
        self.state.set_sim_step(step);
    }

    /// Sets the export form's files (tests; the form is otherwise typed).
    pub fn set_export_paths(&mut self, gcode: &std::path::Path, sheet: &std::path::Path) {
        self.forms.gcode_path = gcode.display().to_string();
        self.forms.sheet_path = sheet.display().to_string();
    }

    /// The feature the inspector's "Add connection" connects to (tests:
    /// the combo box lists every feature).
    pub fn set_connect_to(&mut self, other: StiffnessFeatureId) {
        self.forms.connect_to = Some(other);
    }

    /// The value in the inspector's feed field for one kind of move.
    pub fn set_feed_field(&mut self, region: Region3, feed: f64) {
        if let Some(f) = self.forms.feeds.iter_mut().find(|(r, _)| *r == region) {
            f.1 = feed;
        }
    }

    /// The value in the inspector's spindle field.
    pub fn set_spindle_field(&mut self, rpm: f64) {
        self.forms.spindle = rpm;
    }

    /// Sets the drawn profile's points as if typed (`x, y; …`; tests).
    pub fn set_draw_points(&mut self, text: &str) {
        self.forms.draw_text = text.to_string();
    }

    /// One frame of the whole interface.
    pub fn frame(&mut self, ui: &mut egui::Ui) {
        self.tick(ui.ctx());
        egui::Panel::top("top").show(ui, |ui| self.top_bar(ui));
        egui::Panel::bottom("bottom").show(ui, |ui| {
            self.simulation(ui);
            let msg = self.state.message.lines().next().unwrap_or("").to_string();
            ui.label(RichText::new(msg).small());
        });
        egui::Panel::left("tree")
            .default_size(260.0)
            .show(ui, |ui| {
                ui.label(RichText::new("Plan").strong());
                self.tree(ui);
            });
        egui::Panel::right("inspector")
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    self.setup_and_knowledge(ui);
                    ui.separator();
                    self.inspector(ui);
                });
            });
        egui::CentralPanel::default().show(ui, |ui| {
            let h = ui.available_height();
            let w = ui.available_width();
            ui.allocate_ui(egui::vec2(w, h * 0.6), |ui| {
                self.viewport.ui(ui, &mut self.state);
            });
            ui.separator();
            self.network.ui(ui, &mut self.state);
        });
        self.file_picker(ui.ctx());
    }
}

impl eframe::App for ThinplanApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.frame(ui);
    }
}
