//! The eframe application: panels around the 3D viewport and the network
//! view, all reading one [`AppState`]; a click anywhere changes the one
//! selection every view shows.

use std::collections::BTreeSet;
use std::path::PathBuf;

use eframe::egui::{self, Color32, RichText};
use thinplan_pipeline::SetupRequest;
use thinplan_plan::{
    ConnectionKind, ConstraintKind, Plan, Region3, Stage, StiffnessFeatureId, WallRole,
};

use crate::conditions;
use crate::network::NetworkView;
use crate::relations;
use crate::state::{connection_word, kind_word, AppState, Entity};
use crate::viewport::Viewport;

const ROW_H: f32 = 18.0;

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

/// How the selected stiffness feature stands to the one it is connected to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ConnectAs {
    /// The selected feature is the base; the other is its leaf.
    #[default]
    Base,
    Leaf,
    Crossing,
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

/// What the file picker was opened for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Picking {
    Part,
    Plan,
}

/// The file picker in `dir`, listing folders and parts (STEP or native
/// `.part.ron`) or plans.
fn file_dialog(picking: Picking, dir: PathBuf) -> egui_file::FileDialog {
    // By the whole name: `.part.ron` parts, not the `.labels.ron` beside them.
    let ends = |suffixes: &'static [&'static str]| -> egui_file::Filter<PathBuf> {
        Box::new(move |p: &std::path::Path| {
            let name = p
                .file_name()
                .map(|n| n.to_string_lossy().to_lowercase())
                .unwrap_or_default();
            suffixes.iter().any(|s| name.ends_with(s))
        })
    };
    let (title, filter) = match picking {
        Picking::Part => ("Open a part", ends(&[".step", ".stp", ".part.ron"])),
        Picking::Plan => ("Open a plan", ends(&[".plan.json", ".plan.ron"])),
    };
    let mut d = egui_file::FileDialog::open_file()
        .title(title)
        .initial_path(dir)
        .show_files_filter(filter)
        .show_rename(false)
        .show_new_folder(false)
        .default_size([520.0, 420.0]);
    d.open();
    d
}

/// Where the picker starts: the bundled parts folder for parts when there
/// is one, else the current directory.
fn start_folder(picking: Picking) -> PathBuf {
    let parts = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/parts");
    match (picking, parts.canonicalize()) {
        (Picking::Part, Ok(dir)) if dir.is_dir() => dir,
        _ => std::env::current_dir().unwrap_or_default(),
    }
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

    fn top_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal_wrapped(|ui| {
            ui.label("Part:");
            ui.add(egui::TextEdit::singleline(&mut self.forms.part_source).desired_width(220.0));
            egui::ComboBox::from_id_salt("samples")
                .selected_text("samples")
                .show_ui(ui, |ui| {
                    for (name, _) in thinplan_import::SAMPLES {
                        if ui.selectable_label(false, *name).clicked() {
                            self.forms.part_source = format!("builtin:{name}");
                        }
                    }
                });
            if ui.button("Open part").clicked() {
                let src = self.forms.part_source.trim().to_string();
                self.open_part(&src);
            }
            if ui.button("Browse…").clicked() {
                self.pick(Picking::Part);
            }
            ui.separator();
            let running = self.state.is_running();
            ui.add_enabled_ui(!running, |ui| {
                let next = self.state.session().and_then(|s| s.next_stage());
                let label = match next {
                    Some(s) => format!("Run next stage ({s:?})"),
                    None => "Run next stage".into(),
                };
                if ui.button(label).clicked() {
                    self.state.run_next();
                }
                if ui.button("Run all").clicked() {
                    self.state.run_all();
                }
            });
            if let Some((label, stage)) = self.state.job_progress() {
                ui.spinner();
                ui.label(match stage {
                    Some(s) => format!("{label}: {s:?}…"),
                    None => format!("{label}…"),
                });
                if ui.button("Cancel").clicked() {
                    self.state.cancel();
                }
            }
            ui.separator();
            ui.add_enabled_ui(!running, |ui| {
                let u = self.state.history.undo_label().map(str::to_string);
                let r = self.state.history.redo_label().map(str::to_string);
                if ui
                    .add_enabled(u.is_some(), egui::Button::new("Undo"))
                    .on_hover_text(u.unwrap_or_default())
                    .clicked()
                {
                    self.state.undo();
                }
                if ui
                    .add_enabled(r.is_some(), egui::Button::new("Redo"))
                    .on_hover_text(r.unwrap_or_default())
                    .clicked()
                {
                    self.state.redo();
                }
            });
            ui.separator();
            ui.label("Plan file:");
            ui.add(egui::TextEdit::singleline(&mut self.forms.plan_path).desired_width(160.0));
            if ui.button("Save plan").clicked() {
                let p = PathBuf::from(self.forms.plan_path.trim());
                self.state.save_plan(&p);
            }
            if ui.button("Open plan").clicked() {
                let p = PathBuf::from(self.forms.plan_path.trim());
                if self.state.open_plan(&p) {
                    self.fill_forms_from_plan();
                }
            }
            if ui.button("Browse plans…").clicked() {
                self.pick(Picking::Plan);
            }
        });
        if let Some(p) = self.state.plan() {
            ui.horizontal(|ui| {
                ui.label("Stages done:");
                for s in Stage::ALL {
                    let done = p.stages_done.contains(&s);
                    let text = RichText::new(format!("{s:?}"));
                    ui.label(if done {
                        text.color(Color32::from_rgb(110, 200, 110))
                    } else {
                        text.weak()
                    });
                }
            });
        }
    }

    /// Sets the export form's files (tests; the form is otherwise typed).
    pub fn set_export_paths(&mut self, gcode: &std::path::Path, sheet: &std::path::Path) {
        self.forms.gcode_path = gcode.display().to_string();
        self.forms.sheet_path = sheet.display().to_string();
    }

    /// Sets the drawn profile's points as if typed (`x, y; …`; tests).
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

    pub fn set_draw_points(&mut self, text: &str) {
        self.forms.draw_text = text.to_string();
    }

    fn open_part(&mut self, source: &str) {
        if self.state.open_part(source, &self.setup_request()) {
            self.viewport.camera = Default::default();
            self.forms.gcode_path.clear();
            self.fill_forms_from_plan();
        }
    }

    /// Opens the file picker for a part or a plan.
    pub fn pick(&mut self, what: Picking) {
        self.pick_in(what, start_folder(what));
    }

    /// Opens the file picker for a part or a plan in folder `dir`.
    pub fn pick_in(&mut self, what: Picking, dir: PathBuf) {
        self.file_dialog = Some((what, file_dialog(what, dir)));
    }

    /// Shows the file picker while it is open and opens what was picked.
    fn file_picker(&mut self, ctx: &egui::Context) {
        let Some((what, d)) = &mut self.file_dialog else {
            return;
        };
        let what = *what;
        let picked = if d.show(ctx).selected() {
            d.path().map(|p| p.to_path_buf())
        } else {
            None
        };
        if !d.visible() {
            self.file_dialog = None;
        }
        let Some(path) = picked else { return };
        match what {
            Picking::Part => {
                let src = path.display().to_string();
                self.forms.part_source = src.clone();
                self.open_part(&src);
            }
            Picking::Plan => {
                self.forms.plan_path = path.display().to_string();
                if self.state.open_plan(&path) {
                    self.fill_forms_from_plan();
                }
            }
        }
    }

    fn setup_request(&self) -> SetupRequest {
        SetupRequest {
            setup_file: None,
            up: crate::state::parse_up(&self.forms.up).ok(),
            machine: Some(self.forms.machine.clone()).filter(|s| !s.is_empty()),
            tool_set: Some(self.forms.tool_set.clone()).filter(|s| !s.is_empty()),
            material: Some(self.forms.material.clone()).filter(|s| !s.is_empty()),
        }
    }

    fn setup_and_knowledge(&mut self, ui: &mut egui::Ui) {
        egui::CollapsingHeader::new("Set-up")
            .default_open(false)
            .show(ui, |ui| {
                let Some(k) = self.state.knowledge() else {
                    ui.label("no part open");
                    return;
                };
                let (machines, tools, materials): (Vec<String>, Vec<String>, Vec<String>) = (
                    k.machines.keys().cloned().collect(),
                    k.tool_sets.keys().cloned().collect(),
                    k.materials.keys().cloned().collect(),
                );
                egui::Grid::new("setup").num_columns(2).show(ui, |ui| {
                    ui.label("up (x, y, z)");
                    ui.text_edit_singleline(&mut self.forms.up);
                    ui.end_row();
                    for (label, list, value) in [
                        ("machine", &machines, &mut self.forms.machine),
                        ("tools", &tools, &mut self.forms.tool_set),
                        ("material", &materials, &mut self.forms.material),
                    ] {
                        ui.label(label);
                        egui::ComboBox::from_id_salt(label)
                            .selected_text(value.as_str())
                            .show_ui(ui, |ui| {
                                for m in list {
                                    ui.selectable_value(value, m.clone(), m);
                                }
                            });
                        ui.end_row();
                    }
                });
                if let Err(e) = crate::state::parse_up(&self.forms.up) {
                    ui.colored_label(Color32::LIGHT_RED, e);
                } else if ui.button("Apply set-up").clicked() {
                    let req = self.setup_request();
                    self.state.apply_setup(&req);
                }
            });
        egui::CollapsingHeader::new("Export").show(ui, |ui| self.export_form(ui));
        // Kept open while the knowledge has errors: they must be seen.
        let errors = !self.state.knowledge_status.errors.is_empty();
        egui::CollapsingHeader::new("Knowledge")
            .open(errors.then_some(true))
            .show(ui, |ui| {
                let origin = self
                    .state
                    .knowledge()
                    .map(|k| k.origin.clone())
                    .unwrap_or_default();
                ui.label(format!("in use: {origin}"));
                ui.horizontal(|ui| {
                    ui.label("directory:");
                    ui.text_edit_singleline(&mut self.forms.knowledge_dir);
                });
                ui.horizontal(|ui| {
                    if ui.button("Load / reload").clicked() {
                        let d = PathBuf::from(self.forms.knowledge_dir.trim());
                        self.state.load_knowledge(Some(&d));
                    }
                    if ui.button("Built-in").clicked() {
                        self.state.load_knowledge(None);
                    }
                });
                for e in &self.state.knowledge_status.errors {
                    ui.colored_label(Color32::LIGHT_RED, e);
                }
            });
    }

    fn export_form(&mut self, ui: &mut egui::Ui) {
        let Some(k) = self.state.knowledge() else {
            ui.label("no part open");
            return;
        };
        let posts: Vec<String> = k.posts.keys().cloned().collect();
        if self.forms.post.is_empty() {
            self.forms.post = thinplan_knowledge::DEFAULT_POST.to_string();
        }
        if self.forms.gcode_path.is_empty() {
            let stem = self
                .state
                .plan()
                .map(|p| export_stem(&p.part.source))
                .unwrap_or_else(|| "part".into());
            self.forms.gcode_path = format!("{stem}.ngc");
            self.forms.sheet_path = format!("{stem}.sheet.html");
        }
        egui::Grid::new("export").num_columns(2).show(ui, |ui| {
            ui.label("post");
            egui::ComboBox::from_id_salt("post")
                .selected_text(self.forms.post.as_str())
                .show_ui(ui, |ui| {
                    for p in &posts {
                        ui.selectable_value(&mut self.forms.post, p.clone(), p);
                    }
                });
            ui.end_row();
            ui.label("G-code file");
            ui.add(egui::TextEdit::singleline(&mut self.forms.gcode_path).id_salt("gcode path"));
            ui.end_row();
            ui.label("setup sheet");
            ui.add(egui::TextEdit::singleline(&mut self.forms.sheet_path).id_salt("sheet path"));
            ui.end_row();
        });
        let verification = self.state.plan().and_then(|p| p.verification.as_ref());
        let verdict = verification.map(|v| v.verdict);
        match verification {
            None => {
                ui.label("verdict: not verified (run all stages)");
            }
            Some(v) => {
                let colour = match v.verdict {
                    thinplan_plan::Verdict::Safe => egui::Color32::from_rgb(40, 140, 60),
                    thinplan_plan::Verdict::Incomplete => egui::Color32::from_rgb(190, 130, 20),
                    thinplan_plan::Verdict::Unsafe => egui::Color32::from_rgb(200, 40, 40),
                };
                ui.colored_label(colour, format!("verdict: {}", v.verdict.name()));
                for l in &v.left {
                    ui.label(format!(
                        "left {:.1} mm³ ({})",
                        l.volume_mm3,
                        l.reason.name()
                    ));
                }
                if !v.removed.is_empty() {
                    ui.label(format!(
                        "{} operation(s) removed by the verification",
                        v.removed.len()
                    ));
                }
                for p in v.problems.iter().take(5) {
                    ui.label(format!(
                        "{} by {}",
                        p.kind.name(),
                        p.operation
                            .map_or_else(|| "-".to_string(), |o| o.to_string())
                    ));
                }
            }
        }
        let ready = verdict.is_some_and(|v| v != thinplan_plan::Verdict::Unsafe);
        if ui
            .add_enabled(ready, egui::Button::new("Export G-code and sheet"))
            .on_disabled_hover_text(if verdict.is_some() {
                "the verification found the program unsafe: no program is written"
            } else {
                "run all stages first"
            })
            .clicked()
        {
            let g = PathBuf::from(self.forms.gcode_path.trim());
            let sheet = self.forms.sheet_path.trim();
            let sheet = (!sheet.is_empty()).then(|| PathBuf::from(sheet));
            let post = self.forms.post.clone();
            self.state.export(&g, sheet.as_deref(), &post);
        }
    }

    fn tree(&mut self, ui: &mut egui::Ui) {
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

    fn refill_edit_forms(&mut self) {
        let Some(sel) = self.state.selection else {
            return;
        };
        let key = (sel, self.state.plan_generation);
        if self.forms.filled_for == Some(key) {
            return;
        }
        let Some(plan) = self.state.plan() else {
            return;
        };
        match sel {
            Entity::Stiffness(id) => {
                if let Some(f) = relations::sf(plan, id) {
                    self.forms.thickness = f.thickness.unwrap_or(0.0);
                }
                self.forms.draw_z = drawing::plan_z_range(plan, id);
            }
            Entity::Machining(id) => {
                if let Some(f) = relations::mf(plan, id) {
                    self.forms.z_min = f.shape.z_min;
                    self.forms.z_max = f.shape.z_max;
                    self.forms.split_z = 0.5 * (f.shape.z_min + f.shape.z_max);
                    // A line across the middle of the profile, along its y.
                    let (lo, hi) = profile_box(&f.shape.region.outer);
                    let cx = 0.5 * (lo.x + hi.x);
                    self.forms.split_line = [cx, lo.y - 1.0, cx, hi.y + 1.0];
                    self.forms.merge_with = None;
                    let (a, b) = drawing::plan_z_range(plan, f.owner);
                    self.forms.draw_z = (a, b);
                }
            }
            Entity::Operation(id) => {
                if let Some(o) = plan.operations.iter().find(|o| o.id == id) {
                    self.forms.spindle = o.spindle_rpm;
                    self.forms.feed_ranges = conditions::feeds(o);
                    self.forms.feeds = self
                        .forms
                        .feed_ranges
                        .iter()
                        .map(|&(r, lo, _)| (r, lo))
                        .collect();
                }
            }
            _ => {}
        }
        self.forms.filled_for = Some(key);
    }

    fn inspector(&mut self, ui: &mut egui::Ui) {
        let Some(sel) = self.state.selection else {
            ui.label("Select something in the tree, the 3D view or the network.");
            return;
        };
        self.refill_edit_forms();
        let mut acts = Vec::new();
        let ThinplanApp { state, forms, .. } = self;
        let Some(plan) = state.plan() else { return };
        let plan: &Plan = plan;
        ui.heading(format!("Inspector: {}", relations::name(plan, sel)));
        egui::Grid::new("attributes")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                let mut row = |k: &str, v: String| {
                    ui.label(k);
                    ui.label(v);
                    ui.end_row();
                };
                match sel {
                    Entity::Part => {
                        row("source", plan.part.source.clone());
                        row("format", format!("{:?}", plan.part.format));
                        row("faces", plan.part.summary.faces.to_string());
                        let b = plan.part.summary.bbox;
                        row(
                            "size mm",
                            format!("{:.1} × {:.1} × {:.1}", b[0], b[1], b[2]),
                        );
                        row("volume mm³", format!("{:.0}", plan.part.summary.volume));
                        row(
                            "sha256",
                            plan.part.sha256.chars().take(16).collect::<String>() + "…",
                        );
                    }
                    Entity::Setup => {
                        let s = &plan.setup;
                        row("up", format!("{:.3}, {:.3}, {:.3}", s.up.x, s.up.y, s.up.z));
                        row("machine", s.machine.clone());
                        row("tools", s.tool_set.clone());
                        row("material", s.material.clone());
                    }
                    Entity::Stiffness(id) => {
                        if let Some(f) = relations::sf(plan, id) {
                            row("kind", relations::kind_name(f.kind).into());
                            row("role", f.role.map_or("—".into(), |r| format!("{r:?}")));
                            row(
                                "thickness mm",
                                f.thickness.map_or("—".into(), |t| format!("{t:.3}")),
                            );
                            row("height mm", format!("{:.3}", f.height));
                            row("length mm", format!("{:.3}", f.length));
                            row("faces", format!("{:?}", f.faces));
                            row(
                                "axis",
                                format!("{:.3}, {:.3}, {:.3}", f.axis.x, f.axis.y, f.axis.z),
                            );
                        }
                    }
                    Entity::Machining(id) => {
                        if let Some(f) = relations::mf(plan, id) {
                            row("owner", f.owner.to_string());
                            row(
                                "z range mm",
                                format!("{:.3} – {:.3}", f.shape.z_min, f.shape.z_max),
                            );
                            row(
                                "profile vertices",
                                f.shape.region.outer.vertices.len().to_string(),
                            );
                            row("bottom", format!("{:?}", f.bottom_adjacency));
                        }
                    }
                    Entity::Operation(id) => {
                        if let Some(o) = plan.operations.iter().find(|o| o.id == id) {
                            row("feature", o.feature.to_string());
                            row("method", o.method.clone());
                            row("tool", o.tool.clone());
                            row("spindle rpm", format!("{:.0}", o.spindle_rpm));
                            let limits = state
                                .knowledge()
                                .and_then(|k| conditions::limits(plan, k, o).ok());
                            let flutes = limits.as_ref().and_then(|l| l.flutes);
                            let cutting = limits.as_ref().and_then(|l| l.cutting.clone());
                            if let Some(d) = limits.as_ref().and_then(|l| l.tool_diameter) {
                                let mut v =
                                    format!("{:.0}", conditions::cutting_speed(d, o.spindle_rpm));
                                if let Some(c) = &cutting {
                                    v.push_str(&format!("  (material: {:.0})", c.cutting_speed));
                                }
                                row("cutting speed m/min", v);
                            }
                            for &(r, lo, hi) in &forms.feed_ranges {
                                let mut v = if lo == hi {
                                    format!("{lo:.0}")
                                } else {
                                    format!("{lo:.0} – {hi:.0}")
                                };
                                if let (
                                    Some(z),
                                    Region3::Boundary | Region3::FullCut | Region3::Rest,
                                ) = (flutes, r)
                                {
                                    let fz = conditions::feed_per_tooth(hi, o.spindle_rpm, z);
                                    v.push_str(&format!("  ({fz:.4} mm/tooth)"));
                                }
                                row(&format!("{} feed mm/min", conditions::region_name(r)), v);
                            }
                            if let Some(c) = &cutting {
                                row(
                                    "material feed per tooth mm",
                                    format!(
                                        "roughing {:.4}, finishing {:.4}",
                                        c.feed_per_tooth_roughing, c.feed_per_tooth_finishing
                                    ),
                                );
                            }
                            let pv = |k: &str| o.provenance.values.get(k).copied();
                            for (k, name) in [
                                ("stepover_rest_mm", "stepover rest mm"),
                                ("stepover_boundary_mm", "stepover boundary mm"),
                                ("depth_of_cut_mm", "depth of cut mm"),
                                ("layers", "layers"),
                                ("time_s", "time s"),
                            ] {
                                if let Some(v) = pv(k) {
                                    row(name, format!("{v:.3}"));
                                }
                            }
                            row("moves", o.moves.len().to_string());
                        }
                    }
                }
            });
        ui.separator();
        // Commands on the selection.
        ui.horizontal_wrapped(|ui| {
            let mut hl = None;
            if ui.button("predecessors").clicked() {
                hl = Some(relations::neighbours(plan, sel, false, false));
            }
            if ui.button("all predecessors").clicked() {
                hl = Some(relations::neighbours(plan, sel, false, true));
            }
            if ui.button("successors").clicked() {
                hl = Some(relations::neighbours(plan, sel, true, false));
            }
            if ui.button("all successors").clicked() {
                hl = Some(relations::neighbours(plan, sel, true, true));
            }
            if ui.button("together").clicked() {
                hl = Some(relations::together(plan, sel));
            }
            if ui.button("owned").clicked() {
                hl = Some(relations::owned(plan, sel));
            }
            if let Some(o) = relations::owner(plan, sel) {
                if ui.button("owner").clicked() {
                    acts.push(Act::Select(Some(o)));
                }
            }
            if let Some(h) = hl {
                acts.push(Act::Highlight(h));
            }
        });
        if !state.highlighted.is_empty() {
            ui.horizontal_wrapped(|ui| {
                for e in &state.highlighted {
                    if ui.link(e.to_string()).clicked() {
                        acts.push(Act::Select(Some(*e)));
                    }
                }
            });
        }
        egui::CollapsingHeader::new("why? (provenance)")
            .default_open(true)
            .show(ui, |ui| match relations::provenance(plan, sel) {
                Some(p) => {
                    ui.label(format!("{:?}: {}", p.source, p.rule));
                    for (k, v) in &p.values {
                        ui.label(format!("  {k} = {v}"));
                    }
                    if !p.note.is_empty() {
                        ui.label(&p.note);
                    }
                }
                None => {
                    ui.label(format!("imported from {}", plan.part.source));
                }
            });
        ui.separator();
        editor(ui, forms, plan, sel, &mut acts);
        if let Some(r) = &state.refusal {
            ui.colored_label(Color32::from_rgb(255, 110, 90), r);
        }
        for a in acts {
            self.apply(a);
        }
    }

    fn apply(&mut self, a: Act) {
        let s = &mut self.state;
        match a {
            Act::Select(e) => s.select(e),
            Act::Highlight(h) => {
                s.message = format!("{} highlighted", h.len());
                s.highlight(h);
            }
            Act::Thickness(id, t) => {
                s.set_thickness(id, t);
            }
            Act::Role(id, r) => {
                s.set_role(id, r);
            }
            Act::AddConstraint(a, b, k) => {
                s.add_constraint(a, b, k);
            }
            Act::RemoveConstraint(i) => {
                s.remove_constraint(i);
            }
            Act::Resize(id, lo, hi) => {
                s.resize_machining(id, lo, hi);
            }
            Act::SplitAt(id, z) => {
                s.split_machining_at(id, z);
            }
            Act::SplitLine(id, p, q) => {
                s.split_machining_by_line(id, p, q);
            }
            Act::Merge(a, b) => {
                s.merge_machining(a, b);
            }
            Act::Draw(owner, pts, lo, hi) => {
                if s.add_drawn_machining(owner, &pts, lo, hi) {
                    self.forms.draw_text.clear();
                }
            }
            Act::Spindle(id, rpm) => {
                s.set_spindle(id, rpm);
            }
            Act::Feed(id, r, f) => {
                s.set_feed(id, r, f);
            }
            Act::Connect(base, leaf, k) => {
                s.add_connection(base, leaf, k);
            }
            Act::Disconnect(a, b) => {
                s.remove_connection(a, b);
            }
        }
    }

    fn simulation(&mut self, ui: &mut egui::Ui) {
        let Some(plan) = self.state.plan() else {
            return;
        };
        let n = plan.machining_features.len();
        ui.horizontal(|ui| {
            ui.add_enabled(
                n > 0,
                egui::Checkbox::new(&mut self.simulate, "Sequence simulation"),
            );
            if n == 0 {
                ui.label("(no machining features yet: run the stages)");
                return;
            }
            ui.add_enabled(
                self.simulate,
                egui::Slider::new(&mut self.sim_index, 0..=n - 1).text("step"),
            );
        });
        if let (true, Some(k), Some(knowledge)) =
            (self.simulate, self.state.sim_step, self.state.knowledge())
        {
            let order = relations::machining_order(plan);
            if let Some(id) = order.get(k) {
                let cur = relations::name(plan, Entity::Machining(*id));
                let mut line = format!(
                    "{}/{}: cutting {cur}; {k} removed, {} remaining",
                    k + 1,
                    n,
                    n - k - 1
                );
                let mut bad = false;
                if let Some(r) = relations::deflection_at(plan, knowledge, &order, k) {
                    bad = r.too_large();
                    line.push_str(&format!(
                        "; wall {} deflection {:.5} mm (allowed {:.4}, {:?}{})",
                        r.wall,
                        r.deflection,
                        r.allowed,
                        r.mode,
                        r.planned
                            .map_or(String::new(), |p| format!(", sized for {p:.5}"))
                    ));
                    if bad {
                        line.push_str(" — TOO LARGE");
                    }
                }
                ui.colored_label(
                    if bad {
                        Color32::from_rgb(255, 110, 90)
                    } else {
                        ui.visuals().text_color()
                    },
                    line,
                );
            }
        }
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

fn editor(ui: &mut egui::Ui, forms: &mut Forms, plan: &Plan, sel: Entity, acts: &mut Vec<Act>) {
    match sel {
        Entity::Stiffness(id) => {
            ui.label(RichText::new("Edit").strong());
            ui.horizontal(|ui| {
                ui.label("thickness");
                ui.add(
                    egui::DragValue::new(&mut forms.thickness)
                        .speed(0.01)
                        .range(0.001..=1e4),
                );
                if ui.button("Set thickness").clicked() {
                    acts.push(Act::Thickness(id, forms.thickness));
                }
            });
            let role = relations::sf(plan, id).and_then(|f| f.role);
            ui.horizontal(|ui| {
                ui.label("role");
                for r in [
                    None,
                    Some(WallRole::Web),
                    Some(WallRole::Rib),
                    Some(WallRole::Flange),
                ] {
                    let name = r.map_or("none".to_string(), |r| format!("{r:?}").to_lowercase());
                    if ui.selectable_label(role == r, name).clicked() && role != r {
                        acts.push(Act::Role(id, r));
                    }
                }
            });
            drawing::draw_section(ui, forms, plan, id, acts);
            connections_section(ui, forms, plan, id, acts);
            ui.label(RichText::new("Sequence constraints").strong());
            let mut remove = None;
            for (i, c) in plan.stiffness_constraints.iter().enumerate() {
                if c.first == id || c.second == id {
                    ui.horizontal(|ui| {
                        ui.label(format!(
                            "{} {} {}  ({})",
                            c.first,
                            kind_word(c.kind),
                            c.second,
                            c.provenance.rule
                        ));
                        if ui.small_button("remove").clicked() {
                            remove = Some(i);
                        }
                    });
                }
            }
            if let Some(i) = remove {
                acts.push(Act::RemoveConstraint(i));
            }
            ui.horizontal(|ui| {
                ui.label(format!("{id}"));
                let kind = forms.kind.get_or_insert(ConstraintKind::Before);
                ui.selectable_value(kind, ConstraintKind::Before, "before");
                ui.selectable_value(kind, ConstraintKind::Simultaneous, "with");
                let others: Vec<StiffnessFeatureId> = plan
                    .stiffness_features
                    .iter()
                    .map(|f| f.id)
                    .filter(|o| *o != id)
                    .collect();
                if forms.other.is_none_or(|o| !others.contains(&o)) {
                    forms.other = others.first().copied();
                }
                egui::ComboBox::from_id_salt("other feature")
                    .selected_text(forms.other.map_or(String::new(), |o| o.to_string()))
                    .show_ui(ui, |ui| {
                        for o in &others {
                            ui.selectable_value(&mut forms.other, Some(*o), o.to_string());
                        }
                    });
                if ui.button("Add constraint").clicked() {
                    if let Some(o) = forms.other {
                        let k = forms.kind.unwrap_or(ConstraintKind::Before);
                        acts.push(Act::AddConstraint(id, o, k));
                    }
                }
            });
        }
        Entity::Machining(id) => {
            ui.label(RichText::new("Edit").strong());
            ui.horizontal(|ui| {
                ui.label("z from");
                ui.add(egui::DragValue::new(&mut forms.z_min).speed(0.05));
                ui.label("to");
                ui.add(egui::DragValue::new(&mut forms.z_max).speed(0.05));
                if ui.button("Resize").clicked() {
                    acts.push(Act::Resize(id, forms.z_min, forms.z_max));
                }
            });
            ui.horizontal(|ui| {
                ui.label("at z");
                ui.add(egui::DragValue::new(&mut forms.split_z).speed(0.05));
                if ui.button("Split at height").clicked() {
                    acts.push(Act::SplitAt(id, forms.split_z));
                }
            });
            ui.horizontal(|ui| {
                ui.label("line");
                for v in &mut forms.split_line {
                    ui.add(egui::DragValue::new(v).speed(0.1).max_decimals(3));
                }
            });
            if ui.button("Split by line").clicked() {
                let l = forms.split_line;
                acts.push(Act::SplitLine(
                    id,
                    glam::DVec2::new(l[0], l[1]),
                    glam::DVec2::new(l[2], l[3]),
                ));
            }
            let owner = relations::mf(plan, id).map(|f| f.owner);
            // The other features of the owner, listed only while the list is
            // open (a wall may own thousands).
            let same_owner = || {
                plan.machining_features
                    .iter()
                    .filter(move |f| Some(f.owner) == owner && f.id != id)
                    .map(|f| f.id)
            };
            let valid = |m: thinplan_plan::MachiningFeatureId| {
                m != id && relations::mf(plan, m).is_some_and(|g| Some(g.owner) == owner)
            };
            if forms.merge_with.is_none_or(|m| !valid(m)) {
                forms.merge_with = same_owner().next();
            }
            ui.horizontal(|ui| {
                ui.label("merge with");
                egui::ComboBox::from_id_salt("merge with")
                    .selected_text(forms.merge_with.map_or("—".into(), |m| m.to_string()))
                    .show_ui(ui, |ui| {
                        for m in same_owner() {
                            ui.selectable_value(&mut forms.merge_with, Some(m), m.to_string());
                        }
                    });
                if ui
                    .add_enabled(forms.merge_with.is_some(), egui::Button::new("Merge"))
                    .clicked()
                {
                    if let Some(m) = forms.merge_with {
                        acts.push(Act::Merge(id, m));
                    }
                }
            });
            if let Some(o) = owner {
                drawing::draw_section(ui, forms, plan, o, acts);
            }
        }
        Entity::Operation(id) => {
            ui.label(RichText::new("Edit").strong());
            ui.horizontal(|ui| {
                ui.label("spindle rpm");
                ui.add(
                    egui::DragValue::new(&mut forms.spindle)
                        .speed(10.0)
                        .range(1.0..=1e6),
                );
                if ui.button("Set spindle").clicked() {
                    acts.push(Act::Spindle(id, forms.spindle));
                }
            });
            for (r, feed) in &mut forms.feeds {
                let name = conditions::region_name(*r);
                ui.horizontal(|ui| {
                    ui.label(format!("{name} feed mm/min"));
                    ui.add(egui::DragValue::new(feed).speed(10.0).range(0.0..=1e6));
                    if ui.button(format!("Set {name} feed")).clicked() {
                        acts.push(Act::Feed(id, *r, *feed));
                    }
                });
            }
            ui.label(
                RichText::new(
                    "Stepover and depth of cut shape the tool path: stage 7 builds it for the \
                     whole machining feature from its method in knowledge/methods.ron and cannot \
                     rebuild one operation from the plan. Change the method and reload the \
                     knowledge (the stages run again).",
                )
                .weak(),
            );
        }
        _ => {}
    }
}

/// The connections of stiffness feature `id`, each removable, and a row to
/// connect it to another one.
fn connections_section(
    ui: &mut egui::Ui,
    forms: &mut Forms,
    plan: &Plan,
    id: StiffnessFeatureId,
    acts: &mut Vec<Act>,
) {
    // Closed by default: a web may carry dozens of features.
    let n = plan
        .connections
        .iter()
        .filter(|c| c.base == id || c.leaf == id)
        .count();
    egui::CollapsingHeader::new(format!("Connections of {id} ({n})"))
        .id_salt("connections")
        .show(ui, |ui| {
            for c in plan
                .connections
                .iter()
                .filter(|c| c.base == id || c.leaf == id)
            {
                let other = if c.base == id { c.leaf } else { c.base };
                ui.horizontal(|ui| {
                    ui.label(format!(
                        "{} {} {}  ({})",
                        c.base,
                        connection_word(c.kind),
                        c.leaf,
                        c.provenance.rule
                    ));
                    if ui.small_button(format!("disconnect {other}")).clicked() {
                        acts.push(Act::Disconnect(id, other));
                    }
                });
            }
            ui.horizontal(|ui| {
                ui.label(format!("{id}"));
                let a = &mut forms.connect_as;
                ui.selectable_value(a, ConnectAs::Base, "carries");
                ui.selectable_value(a, ConnectAs::Leaf, "is carried by");
                ui.selectable_value(a, ConnectAs::Crossing, "crosses");
                let others = || {
                    plan.stiffness_features
                        .iter()
                        .map(|f| f.id)
                        .filter(move |o| *o != id)
                };
                if forms
                    .connect_to
                    .is_none_or(|o| o == id || relations::sf(plan, o).is_none())
                {
                    forms.connect_to = others().next();
                }
                egui::ComboBox::from_id_salt("connect to")
                    .selected_text(forms.connect_to.map_or("—".into(), |o| o.to_string()))
                    .show_ui(ui, |ui| {
                        for o in others() {
                            ui.selectable_value(
                                &mut forms.connect_to,
                                Some(o),
                                format!("connect to {o}"),
                            );
                        }
                    });
                if ui.button("Add connection").clicked() {
                    if let Some(o) = forms.connect_to {
                        acts.push(match forms.connect_as {
                            ConnectAs::Base => Act::Connect(id, o, ConnectionKind::BaseLeaf),
                            ConnectAs::Leaf => Act::Connect(o, id, ConnectionKind::BaseLeaf),
                            ConnectAs::Crossing => Act::Connect(id, o, ConnectionKind::Crossing),
                        });
                    }
                }
            });
        });
}

/// What a panel asked for, applied after drawing (the plan is borrowed
/// while drawing, never copied).
enum Act {
    Select(Option<Entity>),
    Highlight(BTreeSet<Entity>),
    Thickness(StiffnessFeatureId, f64),
    Role(StiffnessFeatureId, Option<WallRole>),
    AddConstraint(StiffnessFeatureId, StiffnessFeatureId, ConstraintKind),
    RemoveConstraint(usize),
    Resize(thinplan_plan::MachiningFeatureId, f64, f64),
    SplitAt(thinplan_plan::MachiningFeatureId, f64),
    SplitLine(thinplan_plan::MachiningFeatureId, glam::DVec2, glam::DVec2),
    Merge(
        thinplan_plan::MachiningFeatureId,
        thinplan_plan::MachiningFeatureId,
    ),
    Draw(StiffnessFeatureId, Vec<glam::DVec2>, f64, f64),
    Spindle(thinplan_plan::OperationId, f64),
    Feed(thinplan_plan::OperationId, Region3, f64),
    Connect(StiffnessFeatureId, StiffnessFeatureId, ConnectionKind),
    Disconnect(StiffnessFeatureId, StiffnessFeatureId),
}

/// A file name stem for exports from a part source (`builtin:wing_rib`,
/// `dir/part.step` → `wing_rib`, `part`).
fn export_stem(source: &str) -> String {
    let name = source.trim_start_matches("builtin:");
    let file = std::path::Path::new(name)
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_else(|| "part".into());
    file.split('.')
        .next()
        .filter(|s| !s.is_empty())
        .unwrap_or("part")
        .to_string()
}

/// The bounding box of a loop's vertices.
fn profile_box(l: &thinplan_plan::ProfileLoop) -> (glam::DVec2, glam::DVec2) {
    let mut lo = glam::DVec2::splat(f64::INFINITY);
    let mut hi = glam::DVec2::splat(f64::NEG_INFINITY);
    for v in &l.vertices {
        lo = lo.min(glam::DVec2::new(v.x, v.y));
        hi = hi.max(glam::DVec2::new(v.x, v.y));
    }
    if !lo.is_finite() {
        return (glam::DVec2::ZERO, glam::DVec2::ZERO);
    }
    (lo, hi)
}

/// The inspector's section for drawing a free-shaped machining feature:
/// a plan view of the owner's features where clicks add points, the
/// points as text (typed or clicked), the z range along up.
mod drawing {
    use super::{Act, Forms};
    use crate::edit;
    use eframe::egui::{self, Color32, Pos2, Sense, Stroke};
    use glam::{DVec2, DVec3};
    use thinplan_plan::{Plan, StiffnessFeatureId};

    fn setup_frame(plan: &Plan) -> thinplan_brep::Frame {
        thinplan_brep::Frame::from_axis_ref(DVec3::ZERO, plan.setup.up, None)
    }

    /// The owner's machining features as outlines in the set-up's plan
    /// view (arcs as chords).
    fn outlines(plan: &Plan, owner: StiffnessFeatureId) -> Vec<Vec<DVec2>> {
        let f = setup_frame(plan);
        plan.machining_features
            .iter()
            .filter(|m| m.owner == owner)
            .map(|m| {
                let fr = &m.shape.frame;
                let x = fr.x.normalize_or_zero();
                let y = fr.z.normalize_or_zero().cross(x);
                crate::scene::loop_points(&m.shape.region.outer)
                    .into_iter()
                    .map(|p| {
                        let w = fr.origin + x * p.x + y * p.y;
                        DVec2::new(w.dot(f.x), w.dot(f.y))
                    })
                    .collect()
            })
            .collect()
    }

    /// The z range (along up) the owner's features span; else the part's.
    pub fn plan_z_range(plan: &Plan, owner: StiffnessFeatureId) -> (f64, f64) {
        let f = setup_frame(plan);
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for m in plan.machining_features.iter().filter(|m| m.owner == owner) {
            let o = m.shape.frame.origin.dot(f.z);
            let s = m.shape.frame.z.normalize_or_zero().dot(f.z);
            for z in [o + s * m.shape.z_min, o + s * m.shape.z_max] {
                lo = lo.min(z);
                hi = hi.max(z);
            }
        }
        if lo.is_finite() && hi > lo {
            (lo, hi)
        } else {
            (0.0, 1.0)
        }
    }

    pub fn draw_section(
        ui: &mut egui::Ui,
        forms: &mut Forms,
        plan: &Plan,
        owner: StiffnessFeatureId,
        acts: &mut Vec<Act>,
    ) {
        egui::CollapsingHeader::new(format!("Draw a machining feature of {owner}"))
            .id_salt("draw")
            .show(ui, |ui| {
                let shapes = outlines(plan, owner);
                let points = edit::parse_points(&forms.draw_text);
                let typed: &[DVec2] = points.as_deref().unwrap_or(&[]);
                let (mut lo, mut hi) =
                    (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
                for p in shapes.iter().flatten().chain(typed) {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
                if !lo.is_finite() {
                    let b = plan.part.summary.bbox;
                    (lo, hi) = (DVec2::ZERO, DVec2::new(b[0].max(1.0), b[1].max(1.0)));
                }
                let pad = (hi - lo).max_element() * 0.1 + 1.0;
                (lo, hi) = (lo - DVec2::splat(pad), hi + DVec2::splat(pad));
                let (rect, resp) = ui.allocate_exact_size(
                    egui::vec2(ui.available_width().min(300.0), 180.0),
                    Sense::click(),
                );
                // Named for screen readers and the headless tests.
                resp.widget_info(|| {
                    egui::WidgetInfo::labeled(egui::WidgetType::Other, true, "plan view to draw in")
                });
                let scale = ((rect.width() as f64) / (hi.x - lo.x))
                    .min((rect.height() as f64) / (hi.y - lo.y));
                let to_screen = |p: DVec2| {
                    Pos2::new(
                        rect.min.x + ((p.x - lo.x) * scale) as f32,
                        rect.max.y - ((p.y - lo.y) * scale) as f32,
                    )
                };
                let painter = ui.painter_at(rect);
                painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
                for s in &shapes {
                    let pts: Vec<Pos2> = s.iter().map(|p| to_screen(*p)).collect();
                    painter.add(egui::Shape::closed_line(
                        pts,
                        Stroke::new(1.0, Color32::from_rgb(120, 140, 170)),
                    ));
                }
                let pts: Vec<Pos2> = typed.iter().map(|p| to_screen(*p)).collect();
                if pts.len() > 1 {
                    painter.add(egui::Shape::closed_line(
                        pts.clone(),
                        Stroke::new(1.5, Color32::from_rgb(255, 200, 40)),
                    ));
                }
                for p in &pts {
                    painter.circle_filled(*p, 2.5, Color32::from_rgb(255, 200, 40));
                }
                if let Some(c) = resp.interact_pointer_pos().filter(|_| resp.clicked()) {
                    // Clicks snap to 0.1 mm in the set-up frame.
                    let x = ((c.x - rect.min.x) as f64 / scale + lo.x) * 10.0;
                    let y = ((rect.max.y - c.y) as f64 / scale + lo.y) * 10.0;
                    let sep = if forms.draw_text.trim().is_empty() {
                        ""
                    } else {
                        "; "
                    };
                    forms.draw_text = format!(
                        "{}{sep}{:.1}, {:.1}",
                        forms.draw_text.trim().trim_end_matches(';'),
                        x.round() / 10.0,
                        y.round() / 10.0
                    );
                }
                ui.label("points (x, y; … in the set-up's plan view, mm): click above or type");
                ui.add(egui::TextEdit::singleline(&mut forms.draw_text).id_salt("draw points"));
                ui.horizontal(|ui| {
                    ui.label("z from");
                    ui.add(egui::DragValue::new(&mut forms.draw_z.0).speed(0.05));
                    ui.label("to");
                    ui.add(egui::DragValue::new(&mut forms.draw_z.1).speed(0.05));
                });
                ui.horizontal(|ui| {
                    if ui.button("Clear points").clicked() {
                        forms.draw_text.clear();
                    }
                    match &points {
                        Ok(p) => {
                            if ui.button("Add drawn feature").clicked() {
                                acts.push(Act::Draw(
                                    owner,
                                    p.clone(),
                                    forms.draw_z.0,
                                    forms.draw_z.1,
                                ));
                            }
                        }
                        Err(e) => {
                            ui.colored_label(Color32::LIGHT_RED, e);
                        }
                    }
                });
            });
    }
}

/// The tree's visible rows `(depth, entity, has children)`, shared.
type TreeRows = std::sync::Arc<Vec<(usize, Entity, bool)>>;

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

impl eframe::App for ThinplanApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.frame(ui);
    }
}
