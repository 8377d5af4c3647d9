//! Headless UI tests (egui_kittest, software GL through `.cargo/config.toml`'s
//! `WGPU_BACKEND = "gl"`): the main workflow driven through the widgets,
//! and snapshots of the main views compared within a tolerance.
//! `UPDATE_SNAPSHOTS=1 cargo test -p thinplan-gui` rewrites the pictures.

use eframe::egui::Vec2;
use egui_kittest::kittest::Queryable as _;
use egui_kittest::{Harness, SnapshotOptions};
use thinplan_gui::{conditions, relations, Entity, ThinplanApp};
use thinplan_plan::{
    ConnectionKind, ConstraintKind, ProvenanceSource, Region3, Stage, StiffnessFeatureId,
    StiffnessKind,
};

fn harness(source: &str) -> Harness<'static, ThinplanApp> {
    let source = source.to_string();
    let mut h = Harness::builder()
        .with_size(Vec2::new(1400.0, 900.0))
        .wgpu()
        .build_eframe(move |cc| ThinplanApp::new(cc, &source));
    h.run_steps(2);
    h
}

fn run_all(h: &mut Harness<'static, ThinplanApp>) {
    h.get_by_label("Run all").click();
    h.run_steps(1);
    assert!(h.state().state.is_running() || h.state().state.plan().is_some());
    h.state_mut().state.wait_job();
    h.run_steps(3);
}

fn plan_bytes(h: &Harness<'static, ThinplanApp>) -> Vec<u8> {
    thinplan_plan::io::to_bytes(h.state().state.plan().expect("a plan"))
}

#[test]
fn main_workflow_select_refuse_undo_redo() {
    let mut h = harness("builtin:wing_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().expect("plan").clone();
    assert!(
        plan.stages_done.contains(&Stage::Determine),
        "{}",
        h.state().state.message
    );
    assert!(!plan.machining_features.is_empty());

    // Select a wall in the tree: the 3D and network views show it selected.
    let wall = plan
        .stiffness_features
        .iter()
        .find(|f| f.kind == StiffnessKind::Wall)
        .expect("a wall");
    let e = Entity::Stiffness(wall.id);
    h.get_by_label(&relations::name(&plan, e)).click();
    h.run_steps(2);
    let app = h.state();
    assert_eq!(app.state.selection, Some(e));
    assert_eq!(app.viewport.drawn_selected(), vec![e]);
    assert_eq!(app.network.drawn_selected, vec![e]);

    // A constraint that would close a cycle is refused and the label shows.
    let c = plan
        .stiffness_constraints
        .iter()
        .find(|c| c.kind == ConstraintKind::Before)
        .expect("wing_rib has a before constraint")
        .clone();
    let before = plan_bytes(&h);
    let ok = h
        .state_mut()
        .state
        .add_constraint(c.second, c.first, ConstraintKind::Before);
    assert!(!ok);
    h.get_by_label(&relations::name(&plan, Entity::Stiffness(c.second)))
        .click();
    h.run_steps(2);
    assert!(h.query_all_by_label_contains("refused:").count() >= 1);
    assert!(plan_bytes(&h) == before, "a refused edit changes nothing");

    // An edit through the inspector, then undo and redo restore the plan exactly.
    h.get_by_label(&relations::name(&plan, e)).click();
    h.run_steps(2);
    // The form holds the current thickness: setting it again changes nothing.
    h.get_by_label("Set thickness").click();
    h.run_steps(1);
    assert!(plan_bytes(&h) == before, "a no-op edit changes nothing");
    let t = wall.thickness.unwrap_or(1.0) + 0.5;
    assert!(h.state_mut().state.set_thickness(wall.id, t));
    h.run_steps(2);
    let edited = plan_bytes(&h);
    assert!(edited != before);
    let edited_plan = h.state().state.plan().unwrap().clone();
    assert!(
        !edited_plan.stages_done.contains(&Stage::Sequence),
        "downstream invalidated"
    );
    assert!(
        edited_plan.stages_done.contains(&Stage::Recognise),
        "upstream kept"
    );
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == before, "plans differ");
    h.get_by_label("Redo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited, "plans differ");
    // Re-running recomputes the invalidated stages.
    run_all(&mut h);
    assert!(h
        .state()
        .state
        .plan()
        .unwrap()
        .stages_done
        .contains(&Stage::Determine));
    // ... and undo still walks back through all of it.
    while h.state_mut().state.undo() {}
    assert_eq!(
        h.state().state.plan().unwrap().stages_done,
        vec![Stage::Import, Stage::Setup]
    );
}

#[test]
fn cycle_refusal_names_the_cycle_and_add_remove_are_undoable() {
    let mut h = harness("builtin:wing_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    let before = plan_bytes(&h);
    let c = plan
        .stiffness_constraints
        .iter()
        .find(|c| c.kind == ConstraintKind::Before)
        .expect("a before constraint")
        .clone();
    let st = &mut h.state_mut().state;
    assert!(!st.add_constraint(c.second, c.first, ConstraintKind::Before));
    let refusal = st.refusal.clone().unwrap();
    assert!(
        refusal.contains(&c.first.to_string()) && refusal.contains(&c.second.to_string()),
        "{refusal}"
    );
    // Removing a constraint invalidates determine and is undoable.
    let i = plan
        .stiffness_constraints
        .iter()
        .position(|x| *x == c)
        .unwrap();
    assert!(st.remove_constraint(i));
    assert!(!st.plan().unwrap().stages_done.contains(&Stage::Determine));
    assert!(st.undo());
    assert!(thinplan_plan::io::to_bytes(st.plan().unwrap()) == before);
}

#[test]
fn simulation_and_save_open() {
    let mut h = harness("builtin:tall_rib");
    run_all(&mut h);
    h.get_by_label("Sequence simulation").click();
    h.run_steps(2);
    assert_eq!(h.state().state.sim_step, Some(0));
    assert!(
        h.query_all_by_label_contains("deflection").count() >= 1 || {
            // tall_rib's first feature may be no wall step; the read-out names the cut.
            h.query_all_by_label_contains("cutting").count() >= 1
        }
    );
    let dir = std::env::temp_dir().join(format!("thinplan-gui-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("p.plan.json");
    let before = plan_bytes(&h);
    assert!(h.state_mut().state.save_plan(&path));
    assert!(
        h.state_mut().state.open_plan(&path),
        "{}",
        h.state().state.message
    );
    assert!(plan_bytes(&h) == before, "plans differ");
    let _ = std::fs::remove_dir_all(&dir);
}

fn snapshot_options() -> SnapshotOptions {
    // Software GL is deterministic on one machine; the tolerance absorbs
    // font hinting and rasteriser differences between Mesa versions.
    SnapshotOptions::new()
        .threshold(2.0)
        .max_failed_pixels(2000)
}

#[test]
fn snapshots_of_the_main_views() {
    let mut h = harness("builtin:wing_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    let wall = plan
        .stiffness_features
        .iter()
        .find(|f| f.kind == StiffnessKind::Wall)
        .unwrap();
    let e = Entity::Stiffness(wall.id);
    h.get_by_label(&relations::name(&plan, e)).click();
    h.run_steps(3);
    let mut results = egui_kittest::SnapshotResults::new();
    results.add(h.try_snapshot_options("gui_main", &snapshot_options()));
    // The simulation at a wall step, so the deflection read-out shows.
    let order = relations::machining_order(&plan);
    let k = {
        let st = &h.state().state;
        let knowledge = st.knowledge().unwrap();
        (order.len() / 2..order.len())
            .chain(0..order.len() / 2)
            .find(|&i| relations::deflection_at(&plan, knowledge, &order, i).is_some())
            .expect("a wall step")
    };
    h.state_mut().state.select(None);
    h.state_mut().simulate = true;
    h.state_mut().sim_index = k;
    h.run_steps(3);
    results.add(h.try_snapshot_options("gui_simulation", &snapshot_options()));
    results.unwrap();
}

#[test]
fn a_profile_drawn_by_clicks_in_the_plan_view_becomes_a_feature() {
    let mut h = harness("builtin:tall_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    let n0 = plan.machining_features.len();
    let wall = plan.stiffness_features[0].id;
    h.state_mut().state.select(Some(Entity::Stiffness(wall)));
    h.run();
    h.get_by_label(&format!("Draw a machining feature of {wall}"))
        .click();
    h.run();
    h.get_by_label("plan view to draw in").scroll_to_me();
    h.run();
    let r = h.get_by_label("plan view to draw in").rect();
    // Three clicks: a triangle inside the plan view.
    for (fx, fy) in [(0.3, 0.7), (0.7, 0.7), (0.5, 0.3)] {
        let p = r.min + eframe::egui::vec2(r.width() * fx, r.height() * fy);
        h.hover_at(p);
        h.drag_at(p);
        h.drop_at(p);
        h.run();
    }
    h.get_by_label("Add drawn feature").scroll_to_me();
    h.run();
    h.get_by_label("Add drawn feature").click();
    h.run();
    let after = h.state().state.plan().unwrap().clone();
    assert_eq!(
        after.machining_features.len(),
        n0 + 1,
        "{}",
        h.state().state.message
    );
    let f = after.machining_features.last().unwrap();
    assert_eq!(f.owner, wall);
    assert_eq!(f.shape.region.outer.vertices.len(), 3);
    // Stored counter-clockwise (outer loops are), with an area.
    assert!(thinplan_gui::edit::loop_area(&f.shape.region.outer) > 1.0);
    let v = &f.shape.region.outer.vertices;
    let signed: f64 = (0..3)
        .map(|i| v[i].x * v[(i + 1) % 3].y - v[(i + 1) % 3].x * v[i].y)
        .sum();
    assert!(signed > 0.0);
    assert!(h.state_mut().state.undo());
    assert_eq!(h.state().state.plan().unwrap(), &plan);
}

/// The inspector's machining-feature editing after a split by a line, with
/// the drawing section open (tall_rib; operations dropped by the edit, so
/// no tool paths in the picture).
#[test]
fn snapshot_of_machining_feature_editing() {
    let mut h = harness("builtin:tall_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    let f = plan
        .machining_features
        .iter()
        .max_by(|a, b| {
            let (va, vb) = (
                thinplan_gui::edit::prism_volume(&a.shape),
                thinplan_gui::edit::prism_volume(&b.shape),
            );
            va.total_cmp(&vb).then(b.id.cmp(&a.id))
        })
        .unwrap()
        .clone();
    h.state_mut().state.select(Some(Entity::Machining(f.id)));
    h.run_steps(2);
    h.get_by_label("Split by line").click();
    h.run();
    h.get_by_label_contains("Draw a machining feature").click();
    h.run();
    h.snapshot_options("gui_edit", &snapshot_options());
}

#[test]
fn knowledge_errors_are_listed_with_their_place_and_nothing_is_lost() {
    let mut h = harness("builtin:tall_rib");
    let dir = std::env::temp_dir().join(format!("thinplan-gui-knowledge-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // A copy of the built-in knowledge with one broken file.
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../knowledge");
    copy_dir(&src, &dir);
    std::fs::write(
        dir.join("sizing.ron"),
        "(\n  allowed_deflection: oops,\n)\n",
    )
    .unwrap();
    let before = plan_bytes(&h);
    let st = &mut h.state_mut().state;
    assert!(!st.load_knowledge(Some(&dir)));
    assert!(
        st.knowledge_status
            .errors
            .iter()
            .any(|e| e.contains("sizing.ron:2:")),
        "{:?}",
        st.knowledge_status.errors
    );
    h.run_steps(2);
    assert!(h.query_all_by_label_contains("sizing.ron:2:").count() >= 1);
    assert!(plan_bytes(&h) == before, "a failed load changes nothing");
    // The built-in copy loads again.
    assert!(h.state_mut().state.load_knowledge(None));
    let _ = std::fs::remove_dir_all(&dir);
}

fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            std::fs::create_dir_all(&target).unwrap();
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

fn volume_of(plan: &thinplan_plan::Plan, ids: &[thinplan_plan::MachiningFeatureId]) -> f64 {
    ids.iter()
        .map(|id| {
            let f = relations::mf(plan, *id).expect("feature");
            thinplan_gui::edit::prism_volume(&f.shape)
        })
        .sum()
}

#[test]
fn machining_feature_edits_are_undoable_and_volumes_add_up() {
    let mut h = harness("builtin:tall_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    // The largest feature: room for a split at mid-height and by a line.
    let f = plan
        .machining_features
        .iter()
        .max_by(|a, b| {
            let (va, vb) = (
                thinplan_gui::edit::prism_volume(&a.shape),
                thinplan_gui::edit::prism_volume(&b.shape),
            );
            va.total_cmp(&vb).then(b.id.cmp(&a.id))
        })
        .unwrap()
        .clone();
    let v0 = volume_of(&plan, &[f.id]);
    let n0 = plan.machining_features.len();
    let before = plan_bytes(&h);
    h.state_mut().state.select(Some(Entity::Machining(f.id)));
    h.run_steps(2);

    // Split at height through the inspector (the form holds mid-height).
    h.get_by_label("Split at height").click();
    h.run_steps(2);
    let split = h.state().state.plan().unwrap().clone();
    assert_eq!(
        split.machining_features.len(),
        n0 + 1,
        "{}",
        h.state().state.message
    );
    let new_id = split.machining_features.last().unwrap().id;
    assert!((volume_of(&split, &[f.id, new_id]) - v0).abs() < 1e-9 * v0.max(1.0));
    // Only what is downstream of machining features is invalidated.
    assert!(split.stages_done.contains(&Stage::Resolve));
    assert!(!split.stages_done.contains(&Stage::Operations));
    assert!(split.operations.is_empty() && split.operation_order.is_empty());
    let edited = plan_bytes(&h);
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == before, "undo restores the plan exactly");
    h.get_by_label("Redo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited, "redo re-applies the split");

    // Merge the two parts back: one feature, the original volume.
    assert!(
        h.state_mut().state.merge_machining(f.id, new_id),
        "{}",
        h.state().state.message
    );
    let merged = h.state().state.plan().unwrap().clone();
    assert_eq!(merged.machining_features.len(), n0);
    assert!((volume_of(&merged, &[f.id]) - v0).abs() < 1e-9 * v0.max(1.0));
    let g = relations::mf(&merged, f.id).unwrap();
    assert_eq!(
        (g.shape.z_min, g.shape.z_max),
        (f.shape.z_min, f.shape.z_max)
    );
    assert!(h.state_mut().state.undo());

    // Split by a line through the inspector (the form holds a line across
    // the middle of the profile).
    assert!(h.state_mut().state.undo());
    assert!(plan_bytes(&h) == before);
    h.state_mut().state.select(None);
    h.run_steps(1);
    h.state_mut().state.select(Some(Entity::Machining(f.id)));
    h.run_steps(2);
    h.get_by_label("Split by line").click();
    h.run_steps(2);
    let by_line = h.state().state.plan().unwrap().clone();
    // The original id and the new ones.
    let pieces: Vec<_> = by_line
        .machining_features
        .iter()
        .filter(|m| m.id == f.id || !plan.machining_features.iter().any(|o| o.id == m.id))
        .map(|m| m.id)
        .collect();
    assert!(pieces.len() >= 2, "{}", h.state().state.message);
    assert!((volume_of(&by_line, &pieces) - v0).abs() < 1e-6 * v0.max(1.0));
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == before);

    // A drawn profile becomes a new feature of the wall (typed points, the
    // inspector's button); undo removes it.
    let owner = f.owner;
    h.state_mut().state.select(Some(Entity::Stiffness(owner)));
    h.run_steps(2);
    h.get_by_label(&format!("Draw a machining feature of {owner}"))
        .click();
    // Until the header's opening animation has settled.
    h.run();
    h.state_mut().set_draw_points("0,0; 4,0; 4,3; 0,3");
    h.run();
    // The inspector scrolls: bring the button into view first.
    h.get_by_label("Add drawn feature").scroll_to_me();
    h.run();
    h.get_by_label("Add drawn feature").click();
    h.run_steps(2);
    let drawn = h.state().state.plan().unwrap().clone();
    assert_eq!(
        drawn.machining_features.len(),
        n0 + 1,
        "{}",
        h.state().state.message
    );
    let d = drawn.machining_features.last().unwrap();
    assert_eq!(d.owner, owner);
    let (lo, hi) = (d.shape.z_min, d.shape.z_max);
    assert!(hi > lo);
    assert!((thinplan_gui::edit::prism_volume(&d.shape) - 12.0 * (hi - lo)).abs() < 1e-9);
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(
        plan_bytes(&h) == before,
        "{} / undo {:?} redo {:?}",
        h.state().state.message,
        h.state().state.history.undo_label(),
        h.state().state.history.redo_label()
    );

    // After a split the invalidated stages run again on the edited features.
    assert!(h
        .state_mut()
        .state
        .split_machining_at(f.id, 0.5 * (f.shape.z_min + f.shape.z_max)));
    h.run_steps(2);
    run_all(&mut h);
    let rerun = h.state().state.plan().unwrap().clone();
    assert!(
        rerun.stages_done.contains(&Stage::Order),
        "{}",
        h.state().state.message
    );
    assert_eq!(rerun.machining_features.len(), n0 + 1, "features kept");
}

#[test]
fn export_writes_gcode_that_parses_and_a_sheet_naming_every_operation() {
    let mut h = harness("builtin:tall_rib");
    let dir = std::env::temp_dir().join(format!("thinplan-gui-export-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (gcode, sheet) = (dir.join("tall_rib.ngc"), dir.join("tall_rib.sheet.html"));
    h.state_mut().set_export_paths(&gcode, &sheet);
    // Before the stages have run there is nothing to export.
    assert!(!h.state_mut().state.export(&gcode, Some(&sheet), "linuxcnc"));
    assert!(!gcode.exists());
    run_all(&mut h);
    h.get_by_label("Export").click();
    h.run_steps(2);
    // The verification's verdict is shown before anything is exported.
    let verdict = h
        .state()
        .state
        .plan()
        .unwrap()
        .verification
        .clone()
        .unwrap();
    assert_ne!(verdict.verdict, thinplan_plan::Verdict::Unsafe);
    h.get_by_label(&format!("verdict: {}", verdict.verdict.name()));
    h.get_by_label("Export G-code and sheet").click();
    h.run_steps(2);
    assert!(gcode.exists(), "{}", h.state().state.message);
    let text = std::fs::read_to_string(&gcode).unwrap();
    let program = thinplan_stocksim::parse(&text, "tall_rib.ngc").expect("the G-code parses");
    assert!(!program.moves.is_empty() && program.ended);
    let html = std::fs::read_to_string(&sheet).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    let plan = h.state().state.plan().unwrap().clone();
    assert!(!plan.operations.is_empty());
    for o in &plan.operations {
        assert!(html.contains(&o.id.to_string()), "{} missing", o.id);
    }
    assert!(html.contains("Verification"), "the sheet shows the verdict");
    // Atomic writes leave no temporary files beside them.
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    // The same program as the post function gives directly (same bytes).
    let st = &h.state().state;
    let k = st.knowledge().unwrap();
    let direct = thinplan_post::post(
        &plan,
        k.post("linuxcnc").unwrap(),
        k.tool_set(&plan.setup.tool_set).unwrap(),
    )
    .unwrap();
    assert!(direct.text == text);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_part_opens_through_the_file_picker() {
    let mut h = harness("builtin:tall_rib");
    h.get_by_label("Browse…").click();
    h.run_steps(3);
    // The picker starts in the bundled parts folder, showing parts only
    // (not the `.labels.ron` files beside them).
    assert!(h
        .query_by_label_contains("crossing_ribs.labels.ron")
        .is_none());
    h.get_by_label_contains("crossing_ribs.part.ron").click();
    h.run_steps(2);
    h.get_by_label("Open").click();
    h.run_steps(3);
    let src = h.state().state.plan().unwrap().part.source.clone();
    assert!(
        src.ends_with("crossing_ribs.part.ron"),
        "{src}: {}",
        h.state().state.message
    );
    // A STEP file the same way.
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../step/tests/fixtures")
        .canonicalize()
        .unwrap();
    h.state_mut()
        .pick_in(thinplan_gui::app::Picking::Part, fixtures);
    h.run();
    h.get_by_label_contains("box_mm.step").scroll_to_me();
    h.run();
    h.get_by_label_contains("box_mm.step").click();
    h.run();
    h.get_by_label("Open").click();
    h.run();
    let plan = h.state().state.plan().unwrap();
    assert!(
        plan.part.source.ends_with("box_mm.step"),
        "{}: {}",
        plan.part.source,
        h.state().state.message
    );
    assert_eq!(plan.part.format, thinplan_plan::PartFormat::Step);
}

fn connected(plan: &thinplan_plan::Plan, a: StiffnessFeatureId, b: StiffnessFeatureId) -> bool {
    plan.connections
        .iter()
        .any(|c| (c.base, c.leaf) == (a, b) || (c.base, c.leaf) == (b, a))
}

#[test]
fn connections_are_added_and_removed_in_the_inspector_undoably() {
    let mut h = harness("builtin:wing_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    let before = plan_bytes(&h);
    let ids: Vec<StiffnessFeatureId> = plan.stiffness_features.iter().map(|f| f.id).collect();
    let (a, b) = ids
        .iter()
        .flat_map(|&a| ids.iter().map(move |&b| (a, b)))
        .find(|&(a, b)| a < b && !connected(&plan, a, b))
        .expect("wing_rib has two features not connected");

    // Connect a and b as crossing through the inspector.
    h.state_mut().state.select(Some(Entity::Stiffness(a)));
    h.run_steps(2);
    // The section is closed until opened (it stays open for other features).
    assert!(h.query_by_label("crosses").is_none());
    h.get_by_label_contains(&format!("Connections of {a} ("))
        .scroll_to_me();
    h.run();
    h.get_by_label_contains(&format!("Connections of {a} ("))
        .click();
    // Until the header's opening animation has settled.
    h.run();
    h.state_mut().set_connect_to(b);
    h.get_by_label("crosses").scroll_to_me();
    h.run();
    h.get_by_label("crosses").click();
    h.run_steps(1);
    h.get_by_label("Add connection").click();
    h.run_steps(2);
    let edited_plan = h.state().state.plan().unwrap().clone();
    assert_eq!(
        edited_plan.connections.len(),
        plan.connections.len() + 1,
        "{}",
        h.state().state.message
    );
    let c = edited_plan.connections.last().unwrap();
    assert_eq!((c.base, c.leaf, c.kind), (a, b, ConnectionKind::Crossing));
    assert_eq!(c.provenance.source, ProvenanceSource::User);
    // Only the stages downstream of the connection graph are invalidated.
    assert!(edited_plan.stages_done.contains(&Stage::Recognise));
    assert!(!edited_plan.stages_done.contains(&Stage::Sequence));
    assert_eq!(edited_plan.stiffness_features, plan.stiffness_features);
    assert!(edited_plan.stiffness_constraints.is_empty());
    // What changed is shown: both ends of the connection.
    let changed = h.state().state.changed.clone();
    assert!(changed.contains(&Entity::Stiffness(a)) && changed.contains(&Entity::Stiffness(b)));
    let edited = plan_bytes(&h);
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == before, "undo restores the plan exactly");
    h.get_by_label("Redo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited, "redo re-applies the connection");

    // The same pair the other way round is a duplicate: refused, shown,
    // nothing changed.
    h.state_mut().state.select(Some(Entity::Stiffness(b)));
    h.run_steps(2);
    h.state_mut().set_connect_to(a);
    h.get_by_label("carries").scroll_to_me();
    h.run();
    h.get_by_label("carries").click();
    h.run_steps(1);
    h.get_by_label("Add connection").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited, "a duplicate changes nothing");
    assert!(h.query_all_by_label_contains("already connected").count() >= 1);
    // A feature connected to itself and unknown features are refused.
    let st = &mut h.state_mut().state;
    assert!(!st.add_connection(a, a, ConnectionKind::BaseLeaf));
    assert!(st.refusal.clone().unwrap().contains("itself"));
    assert!(!st.add_connection(a, StiffnessFeatureId(999_999), ConnectionKind::BaseLeaf));
    assert!(st
        .refusal
        .clone()
        .unwrap()
        .contains("no stiffness feature SF999999"));
    assert!(!st.remove_connection(StiffnessFeatureId(999_999), a));
    assert!(plan_bytes(&h) == edited, "refusals change nothing");

    // Disconnect through the inspector; undo brings the connection back.
    h.state_mut().state.select(Some(Entity::Stiffness(a)));
    h.run_steps(2);
    h.get_by_label(&format!("disconnect {b}")).scroll_to_me();
    h.run();
    h.get_by_label(&format!("disconnect {b}")).click();
    h.run_steps(2);
    let removed = h.state().state.plan().unwrap().clone();
    assert!(!connected(&removed, a, b), "{}", h.state().state.message);
    assert_eq!(removed.connections, plan.connections);
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited);

    // The invalidated stages run again with the new connection kept.
    run_all(&mut h);
    let rerun = h.state().state.plan().unwrap().clone();
    assert!(
        rerun.stages_done.contains(&Stage::Order),
        "{}",
        h.state().state.message
    );
    assert!(connected(&rerun, a, b));
}

#[test]
fn operation_conditions_are_edited_in_the_inspector_checked_and_undoable() {
    let mut h = harness("builtin:tall_rib");
    run_all(&mut h);
    let plan = h.state().state.plan().unwrap().clone();
    assert!(plan.stages_done.contains(&Stage::Order));
    let k = h.state().state.knowledge().unwrap().clone();
    // The time the inspector recomputes agrees with stage 7's own.
    for o in &plan.operations {
        let l = conditions::limits(&plan, &k, o).unwrap();
        let t = conditions::time_s(o, &l.motion);
        let t7 = o.provenance.values["time_s"];
        assert!(
            (t - t7).abs() <= 0.03 * t7,
            "{}: {t} s vs stage 7 {t7} s",
            o.id
        );
    }
    let op = plan
        .operations
        .iter()
        .find(|o| {
            conditions::feeds(o)
                .iter()
                .any(|(r, lo, hi)| *r == Region3::Boundary && lo == hi)
        })
        .expect("an operation with boundary moves")
        .clone();
    let old = conditions::feeds(&op)
        .into_iter()
        .find(|(r, _, _)| *r == Region3::Boundary)
        .unwrap()
        .1;
    let before = plan_bytes(&h);
    h.state_mut().state.select(Some(Entity::Operation(op.id)));
    h.run_steps(2);
    assert!(h
        .query_by_label_contains("cannot rebuild one operation")
        .is_some());
    assert!(h.query_by_label("cutting speed m/min").is_some());
    // In the attribute table and beside its edit field.
    assert_eq!(h.query_all_by_label("boundary feed mm/min").count(), 2);

    // Halve the boundary feed through the inspector.
    let new = (old * 0.5).round();
    h.state_mut().set_feed_field(Region3::Boundary, new);
    h.get_by_label("Set boundary feed").scroll_to_me();
    h.run();
    h.get_by_label("Set boundary feed").click();
    h.run_steps(2);
    let edited_plan = h.state().state.plan().unwrap().clone();
    let e = edited_plan
        .operations
        .iter()
        .find(|o| o.id == op.id)
        .unwrap();
    assert_eq!(e.moves.len(), op.moves.len());
    for (m, m0) in e.moves.iter().zip(&op.moves) {
        let want = if m0.region == Region3::Boundary {
            new
        } else {
            m0.feed
        };
        assert_eq!(m.feed, want, "{}", h.state().state.message);
        assert_eq!((m.to, m.arc, m.region), (m0.to, m0.arc, m0.region));
    }
    assert!(e.provenance.values["time_s"] > op.provenance.values["time_s"]);
    assert_eq!(
        e.provenance.values["layers"],
        op.provenance.values["layers"]
    );
    assert_eq!(e.provenance.source, ProvenanceSource::User);
    // Nothing upstream of the program is invalidated: the order stays.
    assert_eq!(edited_plan.stages_done, plan.stages_done);
    assert_eq!(edited_plan.operation_order, plan.operation_order);
    for (o, o0) in edited_plan.operations.iter().zip(&plan.operations) {
        assert!(o.id == op.id || o == o0, "{} changed too", o.id);
    }
    assert!(h.state().state.changed.contains(&Entity::Operation(op.id)));
    // The program carries the new feed (the post writes whole mm/min).
    let post = k.post("linuxcnc").unwrap();
    let tools = k.tool_set(&plan.setup.tool_set).unwrap();
    let word = format!("F{new:.0}");
    let count = |p: &thinplan_plan::Plan| {
        let text = thinplan_post::post(p, post, tools).unwrap().text;
        text.split_whitespace().filter(|w| *w == word).count()
    };
    assert!(count(&edited_plan) > count(&plan), "{word}");
    let edited = plan_bytes(&h);
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == before, "undo restores the plan exactly");
    h.get_by_label("Redo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited, "redo re-applies the feed");

    // Invalid values are refused with a message and change nothing.
    h.state_mut().set_feed_field(Region3::Boundary, 0.0);
    h.get_by_label("Set boundary feed").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited);
    assert!(
        h.query_all_by_label_contains("must be a positive number")
            .count()
            >= 1
    );
    let machine = k.machine(&plan.setup.machine).unwrap().clone();
    let st = &mut h.state_mut().state;
    assert!(!st.set_feed(op.id, Region3::Boundary, f64::NAN));
    assert!(!st.set_feed(op.id, Region3::Boundary, machine.x.v_max * 60.0 * 10.0));
    assert!(
        st.message.contains("faster than any axis"),
        "{}",
        st.message
    );
    assert!(!st.set_spindle(op.id, machine.spindle_max_rpm + 1.0));
    assert!(st.message.contains("above machine"), "{}", st.message);
    assert!(!st.set_spindle(op.id, f64::INFINITY));
    assert!(!st.set_feed(
        thinplan_plan::OperationId(999_999),
        Region3::Boundary,
        100.0
    ));
    assert!(plan_bytes(&h) == edited, "refusals change nothing");

    // The spindle through the inspector: the moves stay as they are.
    let rpm = (op.spindle_rpm * 0.9).round();
    h.state_mut().set_spindle_field(rpm);
    h.get_by_label("Set spindle").click();
    h.run_steps(2);
    let spun = h.state().state.plan().unwrap().clone();
    let s = spun.operations.iter().find(|o| o.id == op.id).unwrap();
    assert_eq!(s.spindle_rpm, rpm, "{}", h.state().state.message);
    assert_eq!(s.moves, e.moves);
    assert_eq!(spun.stages_done, plan.stages_done);
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert!(plan_bytes(&h) == edited);
}
