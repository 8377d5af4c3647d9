//! thinplan's desktop application: a tree, a 3D viewport, a
//! network view of sequence constraints and an inspector over one plan,
//! with undoable edits, stage runs in a background thread and a sequence
//! simulation. The application owns no planning logic: stages run through
//! `thinplan-pipeline`, edits go through the plan's own invalidation and
//! `thinplan-sequence`'s cycle check.

pub mod app;
pub mod conditions;
pub mod edit;
pub mod network;
pub mod relations;
pub mod render;
pub mod scene;
pub mod state;
pub mod viewport;

pub use app::ThinplanApp;
pub use state::{AppState, Entity};

/// The part opened when none is named.
pub fn default_source() -> String {
    format!("builtin:{}", thinplan_import::DEFAULT_SAMPLE)
}

/// Opens the application window on `source` (a part file or `builtin:NAME`).
pub fn run(source: String) -> eframe::Result<()> {
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_inner_size([1400.0, 900.0])
            .with_title("thinplan"),
        ..Default::default()
    };
    eframe::run_native(
        "thinplan",
        options,
        Box::new(move |cc| Ok(Box::new(ThinplanApp::new(cc, &source)))),
    )
}
