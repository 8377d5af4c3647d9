//! Opening parts and plans: the in-window file picker and what it was
//! opened for.

use std::path::PathBuf;

use eframe::egui;

use super::ThinplanApp;

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
    pub(super) fn open_part(&mut self, source: &str) {
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
    pub(super) fn file_picker(&mut self, ctx: &egui::Context) {
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
}
