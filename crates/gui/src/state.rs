//! The application's state without any drawing: the session, the selection,
//! the editing history, the background job and the simulation position.
//! Every view reads from here; tests drive it directly.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use glam::DVec3;
use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{ErrorKind, PipelineError, Session, SetupRequest};
use thinplan_plan::{
    Connection, ConnectionKind, Constraint, ConstraintKind, MachiningFeatureId, OperationId, Plan,
    Provenance, ProvenanceSource, Stage, StiffnessFeatureId,
};

/// One thing a view can show and select.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Entity {
    Part,
    Setup,
    Stiffness(StiffnessFeatureId),
    Machining(MachiningFeatureId),
    Operation(OperationId),
}

impl std::fmt::Display for Entity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Entity::Part => write!(f, "part"),
            Entity::Setup => write!(f, "set-up"),
            Entity::Stiffness(id) => write!(f, "{id}"),
            Entity::Machining(id) => write!(f, "{id}"),
            Entity::Operation(id) => write!(f, "{id}"),
        }
    }
}

/// Where the knowledge came from and what went wrong loading it.
#[derive(Debug, Clone, Default)]
pub struct KnowledgeStatus {
    /// `None`: the built-in copy.
    pub dir: Option<PathBuf>,
    /// One line per problem, each starting with file:line:column.
    pub errors: Vec<String>,
}

/// A stage run going on in a background thread; the session travels with it.
struct Job {
    handle: JoinHandle<(Session, Result<(), PipelineError>)>,
    cancel: Arc<AtomicBool>,
    progress: Arc<Mutex<Option<Stage>>>,
    label: String,
    before: Plan,
}

/// An entry of the editing history: what was done and the plan before it.
#[derive(Clone)]
struct Snapshot {
    label: String,
    plan: Plan,
}

/// The undo/redo history over whole-plan snapshots: simple and exact (the
/// serialised plan after undo is the one before the edit, byte for byte).
#[derive(Default)]
pub struct History {
    undo: Vec<Snapshot>,
    redo: Vec<Snapshot>,
}

impl History {
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|s| s.label.as_str())
    }
    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|s| s.label.as_str())
    }
    pub fn len(&self) -> usize {
        self.undo.len()
    }
    pub fn is_empty(&self) -> bool {
        self.undo.is_empty()
    }
}

/// The whole application state.
pub struct AppState {
    /// `None` only while a job holds the session, or when no part opened.
    session: Option<Session>,
    /// What the views show while a job runs (the plan before it).
    shown_while_running: Option<Plan>,
    job: Option<Job>,
    pub knowledge_status: KnowledgeStatus,
    pub selection: Option<Entity>,
    /// Entities a command (predecessors, owned …) asked to highlight.
    pub highlighted: BTreeSet<Entity>,
    /// What the last stage run or edit changed or added.
    pub changed: BTreeSet<Entity>,
    pub history: History,
    /// The last message for the status line (errors included).
    pub message: String,
    /// The last refusal of an edit, with the cycle it would have made.
    pub refusal: Option<String>,
    /// Counts plan changes so views rebuild their geometry only then.
    pub plan_generation: u64,
    /// Counts selection/highlight/simulation changes (cheap restyling).
    pub style_generation: u64,
    /// Simulation position: how many machining features of the order are done.
    pub sim_step: Option<usize>,
}

impl Default for AppState {
    fn default() -> Self {
        AppState {
            session: None,
            shown_while_running: None,
            job: None,
            knowledge_status: KnowledgeStatus::default(),
            selection: None,
            highlighted: BTreeSet::new(),
            changed: BTreeSet::new(),
            history: History::default(),
            message: String::new(),
            refusal: None,
            plan_generation: 1,
            style_generation: 1,
            sim_step: None,
        }
    }
}

impl AppState {
    /// Opens `source` (a part file or `builtin:NAME`) with the built-in
    /// knowledge and the default set-up; an error is kept in `message`.
    pub fn open_default(source: &str) -> AppState {
        let mut s = AppState::default();
        s.open_part(source, &SetupRequest::default());
        s
    }

    pub fn plan(&self) -> Option<&Plan> {
        match &self.session {
            Some(s) => Some(&s.plan),
            None => self.shown_while_running.as_ref(),
        }
    }

    /// Replaces the plan as a new document (no history), e.g. a plan made
    /// elsewhere for the same part.
    pub fn replace_plan(&mut self, plan: Plan) -> bool {
        if self.is_running() {
            return false;
        }
        let Some(s) = &mut self.session else {
            return false;
        };
        s.plan = plan;
        self.after_new_document();
        true
    }

    pub fn session(&self) -> Option<&Session> {
        self.session.as_ref()
    }

    pub fn knowledge(&self) -> Option<&Knowledge> {
        self.session.as_ref().map(|s| &s.knowledge)
    }

    pub fn is_running(&self) -> bool {
        self.job.is_some()
    }

    /// The stage the job is running, if any, and its label.
    pub fn job_progress(&self) -> Option<(String, Option<Stage>)> {
        self.job.as_ref().map(|j| {
            let stage = j.progress.lock().map(|p| *p).unwrap_or(None);
            (j.label.clone(), stage)
        })
    }

    fn knowledge_for_open(&mut self) -> Result<Knowledge, PipelineError> {
        if let Some(s) = &self.session {
            return Ok(s.knowledge.clone());
        }
        thinplan_pipeline::load_knowledge(self.knowledge_status.dir.as_deref())
    }

    /// Opens a part; the history starts anew (another part is another document).
    pub fn open_part(&mut self, source: &str, req: &SetupRequest) -> bool {
        if self.is_running() {
            self.message = "a stage is running: cancel it first".into();
            return false;
        }
        let result = self.knowledge_for_open().and_then(|k| {
            let setup = thinplan_pipeline::make_setup(req, &k)?;
            Session::open(source, setup, k)
        });
        match result {
            Ok(session) => {
                self.message = format!("opened {source}");
                self.message
                    .extend(session.warnings.iter().map(|w| format!("\n{w}")));
                self.session = Some(session);
                self.after_new_document();
                true
            }
            Err(e) => {
                self.message = format!("cannot open {source}: {}", e.message);
                false
            }
        }
    }

    fn after_new_document(&mut self) {
        self.history = History::default();
        self.selection = None;
        self.highlighted.clear();
        self.changed.clear();
        self.refusal = None;
        self.sim_step = None;
        self.bump_plan();
    }

    fn bump_plan(&mut self) {
        self.plan_generation += 1;
        self.style_generation += 1;
    }

    pub fn bump_style(&mut self) {
        self.style_generation += 1;
    }

    pub fn select(&mut self, e: Option<Entity>) {
        if self.selection != e {
            self.selection = e;
            self.highlighted.clear();
            self.bump_style();
        }
    }

    pub fn highlight(&mut self, set: BTreeSet<Entity>) {
        self.highlighted = set;
        self.bump_style();
    }

    pub fn set_sim_step(&mut self, step: Option<usize>) {
        if self.sim_step != step {
            self.sim_step = step;
            self.bump_style();
        }
    }

    // ------------------------------------------------------------------
    // Knowledge

    /// Loads the knowledge from `dir` (or the built-in copy); on errors the
    /// current knowledge stays and the errors are listed. A new knowledge
    /// invalidates every stage after the set-up (undoable).
    pub fn load_knowledge(&mut self, dir: Option<&Path>) -> bool {
        if self.is_running() {
            self.message = "a stage is running: cancel it first".into();
            return false;
        }
        self.knowledge_status.dir = dir.map(Path::to_path_buf);
        match thinplan_pipeline::load_knowledge(dir) {
            Ok(k) => {
                self.knowledge_status.errors.clear();
                let origin = k.origin.clone();
                if let Some(s) = &mut self.session {
                    s.knowledge = k;
                }
                self.edit(&format!("knowledge from {origin}"), |plan| {
                    plan.notes.insert("knowledge".into(), origin.clone());
                    Ok(Stage::Recognise)
                });
                self.message = format!("knowledge loaded from {origin}");
                true
            }
            Err(e) => {
                self.knowledge_status.errors = e.message.lines().map(str::to_string).collect();
                self.message = format!(
                    "knowledge not loaded: {} problem(s)",
                    self.knowledge_status.errors.len()
                );
                false
            }
        }
    }

    // ------------------------------------------------------------------
    // Set-up

    /// Stage 1 again with new choices; the stages after it are invalidated.
    pub fn apply_setup(&mut self, req: &SetupRequest) -> bool {
        let Some(session) = &self.session else {
            return false;
        };
        let setup = thinplan_pipeline::make_setup(req, &session.knowledge).and_then(|mut s| {
            thinplan_pipeline::check_fits(&session.plan.part, &s, &session.knowledge)?;
            s.provenance.rule = "gui.setup".into();
            Ok(s)
        });
        match setup {
            Ok(setup) => self.edit("set-up", move |plan| {
                plan.setup = setup.clone();
                Ok(Stage::Recognise)
            }),
            Err(e) => {
                self.message = format!("set-up refused: {}", e.message);
                false
            }
        }
    }

    // ------------------------------------------------------------------
    // Running stages

    /// Starts running the stages up to `last` in a background thread.
    pub fn start_run(&mut self, last: Stage, label: &str) -> bool {
        if self.is_running() {
            return false;
        }
        let Some(mut session) = self.session.take() else {
            self.message = "no part open".into();
            return false;
        };
        let before = session.plan.clone();
        self.shown_while_running = Some(before.clone());
        let cancel = Arc::new(AtomicBool::new(false));
        let progress = Arc::new(Mutex::new(None));
        let (c, p) = (cancel.clone(), progress.clone());
        let handle = std::thread::spawn(move || {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                session.run_to(last, &c, |stage| {
                    if let Ok(mut g) = p.lock() {
                        *g = Some(stage);
                    }
                })
            }));
            let r = r.unwrap_or_else(|_| {
                Err(PipelineError {
                    kind: ErrorKind::Stage,
                    message: "a stage panicked (a bug); the plan before it is kept".into(),
                })
            });
            (session, r)
        });
        self.job = Some(Job {
            handle,
            cancel,
            progress,
            label: label.into(),
            before,
        });
        self.message = format!("{label}…");
        true
    }

    /// Runs the next stage the plan needs.
    pub fn run_next(&mut self) -> bool {
        match self.session.as_ref().and_then(|s| s.next_stage()) {
            Some(stage) if stage <= thinplan_pipeline::LAST_BUILT => {
                self.start_run(stage, &format!("run {stage:?}"))
            }
            Some(stage) => {
                self.message = format!("{stage:?} is not built yet");
                false
            }
            None => {
                self.message = "every stage has run".into();
                false
            }
        }
    }

    pub fn run_all(&mut self) -> bool {
        self.start_run(thinplan_pipeline::LAST_BUILT, "run all stages")
    }

    pub fn cancel(&mut self) {
        if let Some(j) = &self.job {
            j.cancel.store(true, Ordering::Relaxed);
        }
    }

    /// Takes the session back when the job has ended; `true` when it did.
    pub fn poll_job(&mut self) -> bool {
        if !self.job.as_ref().is_some_and(|j| j.handle.is_finished()) {
            return false;
        }
        self.finish_job();
        true
    }

    /// Waits for the job to end (tests, benchmarks).
    pub fn wait_job(&mut self) {
        if self.job.is_some() {
            self.finish_job();
        }
    }

    fn finish_job(&mut self) {
        let Some(job) = self.job.take() else { return };
        self.shown_while_running = None;
        match job.handle.join() {
            Ok((mut session, result)) => {
                let failed_stage = job.progress.lock().map(|p| *p).unwrap_or(None);
                match result {
                    Ok(()) => self.message = format!("{}: done", job.label),
                    Err(e) if e.kind == ErrorKind::Cancelled => {
                        self.message = format!("{}: cancelled", job.label)
                    }
                    Err(e) => {
                        // A failing stage leaves the plan as it was before it.
                        self.message = format!(
                            "{}: {:?} failed: {}",
                            job.label,
                            failed_stage.unwrap_or(Stage::Import),
                            e.message
                        );
                    }
                }
                if session.plan != job.before {
                    self.changed = changes(&job.before, &session.plan);
                    self.history.undo.push(Snapshot {
                        label: job.label,
                        plan: job.before,
                    });
                    self.history.redo.clear();
                } else if session.plan.stages_done != job.before.stages_done {
                    self.changed.clear();
                }
                session.warnings.clear();
                self.session = Some(session);
                self.sim_step = None;
                self.bump_plan();
            }
            Err(_) => {
                self.message = "the stage thread died; the part must be opened again".into();
            }
        }
    }

    // ------------------------------------------------------------------
    // Editing

    /// Applies an edit to a copy of the plan; on success the copy replaces
    /// the plan, the stages from the returned one on are invalidated and the
    /// old plan goes on the undo stack. An `Err` is shown and changes nothing.
    pub fn edit(
        &mut self,
        label: &str,
        f: impl FnOnce(&mut Plan) -> Result<Stage, String>,
    ) -> bool {
        if self.is_running() {
            self.message = "a stage is running: edits wait until it ends".into();
            return false;
        }
        let Some(session) = &mut self.session else {
            return false;
        };
        let mut next = session.plan.clone();
        match f(&mut next) {
            Ok(from) => {
                // An edit that changes nothing invalidates nothing.
                if next == session.plan {
                    return true;
                }
                next.invalidate_from(from);
                let before = std::mem::replace(&mut session.plan, next);
                self.changed = changes(&before, &session.plan);
                self.history.undo.push(Snapshot {
                    label: label.into(),
                    plan: before,
                });
                self.history.redo.clear();
                self.message = format!("{label} (stages from {from:?} on to run again)");
                self.refusal = None;
                self.bump_plan();
                true
            }
            Err(e) => {
                self.message = format!("{label}: {e}");
                false
            }
        }
    }

    pub fn undo(&mut self) -> bool {
        self.step_history(true)
    }

    pub fn redo(&mut self) -> bool {
        self.step_history(false)
    }

    fn step_history(&mut self, undo: bool) -> bool {
        if self.is_running() {
            return false;
        }
        let Some(session) = &mut self.session else {
            return false;
        };
        let (from, to) = if undo {
            (&mut self.history.undo, &mut self.history.redo)
        } else {
            (&mut self.history.redo, &mut self.history.undo)
        };
        let Some(snap) = from.pop() else {
            return false;
        };
        let current = std::mem::replace(&mut session.plan, snap.plan);
        self.changed = changes(&current, &session.plan);
        self.message = format!("{} {}", if undo { "undid" } else { "redid" }, snap.label);
        to.push(Snapshot {
            label: snap.label,
            plan: current,
        });
        self.refusal = None;
        self.sim_step = None;
        self.bump_plan();
        true
    }

    /// Sets a stiffness feature's thickness; sequencing and later re-run.
    pub fn set_thickness(&mut self, id: StiffnessFeatureId, t: f64) -> bool {
        self.edit(&format!("{id} thickness {t:.3}"), |plan| {
            if !(t.is_finite() && t > 0.0) {
                return Err(format!("thickness must be a positive number, not {t}"));
            }
            let f = find_sf(plan, id)?;
            if f.thickness == Some(t) {
                return Ok(Stage::Sequence);
            }
            let was = f.thickness;
            f.thickness = Some(t);
            f.provenance = user_edit("gui.edit.thickness", &f.provenance, was);
            Ok(Stage::Sequence)
        })
    }

    /// Sets a wall's role (web, rib, flange, or none).
    pub fn set_role(
        &mut self,
        id: StiffnessFeatureId,
        role: Option<thinplan_plan::WallRole>,
    ) -> bool {
        self.edit(&format!("{id} role {role:?}"), |plan| {
            let f = find_sf(plan, id)?;
            if f.role == role {
                return Ok(Stage::Sequence);
            }
            f.role = role;
            f.provenance = user_edit("gui.edit.role", &f.provenance, None);
            Ok(Stage::Sequence)
        })
    }

    /// Adds a stiffness constraint by hand; one that would close a cycle
    /// (or split a simultaneous group) is refused with the cycle shown.
    pub fn add_constraint(
        &mut self,
        first: StiffnessFeatureId,
        second: StiffnessFeatureId,
        kind: ConstraintKind,
    ) -> bool {
        let Some(plan) = self.plan() else {
            return false;
        };
        if first == second {
            self.refusal = Some(format!("refused: {first} cannot be constrained to itself"));
            return false;
        }
        let mut seq = thinplan_sequence::Sequencing::from_plan(plan);
        let c = Constraint {
            first,
            second,
            kind,
            priority: 0,
            provenance: Provenance::new(ProvenanceSource::User, "gui.constraint"),
        };
        match thinplan_sequence::try_add(&mut seq, c) {
            Ok(()) => {
                let constraints = seq.constraints;
                let word = kind_word(kind);
                let ok = self.edit(&format!("{first} {word} {second}"), move |plan| {
                    plan.stiffness_constraints = constraints;
                    Ok(Stage::Determine)
                });
                self.refusal = None;
                ok
            }
            Err(r) => {
                self.refusal = Some(format!("refused: {}", r.reason));
                self.message = self.refusal.clone().unwrap_or_default();
                false
            }
        }
    }

    /// Removes the stiffness constraint at `index`.
    pub fn remove_constraint(&mut self, index: usize) -> bool {
        self.edit("remove constraint", |plan| {
            if index >= plan.stiffness_constraints.len() {
                return Err("no such constraint".into());
            }
            plan.stiffness_constraints.remove(index);
            Ok(Stage::Determine)
        })
    }

    /// A machining-feature edit: operations and order recompute (resolve
    /// too when it has not run yet); a refusal (a cycle) is shown as one.
    /// The features the edit made or changed are selected and highlighted.
    fn mf_edit(
        &mut self,
        label: &str,
        f: impl FnOnce(&mut Plan) -> Result<Vec<MachiningFeatureId>, String>,
    ) -> bool {
        let mut made = Vec::new();
        let ok = self.edit(label, |plan| {
            let from = crate::edit::invalidated_from(plan);
            made = f(plan)?;
            Ok(from)
        });
        if ok {
            if let Some(first) = made.first() {
                self.select(Some(Entity::Machining(*first)));
            }
            self.highlight(made.iter().map(|i| Entity::Machining(*i)).collect());
        } else if self.message.contains("refused") {
            self.refusal = Some(self.message.clone());
        }
        ok
    }

    /// Splits a machining feature at height `z` of its sweep axis.
    pub fn split_machining_at(&mut self, id: MachiningFeatureId, z: f64) -> bool {
        self.mf_edit(&format!("split {id} at z {z:.3}"), |plan| {
            crate::edit::split_at_height(plan, id, z)
        })
    }

    /// Splits a machining feature by the line through `p` and `q` (its
    /// profile's coordinates).
    pub fn split_machining_by_line(
        &mut self,
        id: MachiningFeatureId,
        p: glam::DVec2,
        q: glam::DVec2,
    ) -> bool {
        self.mf_edit(&format!("split {id} by a line"), |plan| {
            crate::edit::split_by_line(plan, id, p, q)
        })
    }

    /// Merges two adjacent machining features of one owner.
    pub fn merge_machining(&mut self, a: MachiningFeatureId, b: MachiningFeatureId) -> bool {
        self.mf_edit(&format!("merge {a} and {b}"), |plan| {
            crate::edit::merge(plan, a, b).map(|m| vec![m])
        })
    }

    /// A new machining feature of `owner` from a profile drawn in the
    /// set-up's plan view.
    pub fn add_drawn_machining(
        &mut self,
        owner: StiffnessFeatureId,
        points: &[glam::DVec2],
        z_min: f64,
        z_max: f64,
    ) -> bool {
        self.mf_edit(&format!("draw a machining feature of {owner}"), |plan| {
            crate::edit::add_drawn(plan, owner, points, z_min, z_max).map(|m| vec![m])
        })
    }

    /// Resizes a machining feature along its sweep axis.
    pub fn resize_machining(&mut self, id: MachiningFeatureId, z_min: f64, z_max: f64) -> bool {
        self.edit(&format!("{id} z {z_min:.3}–{z_max:.3}"), |plan| {
            let from = crate::edit::invalidated_from(plan);
            if !(z_min.is_finite() && z_max.is_finite() && z_max > z_min) {
                return Err(format!("z range {z_min}–{z_max} is empty"));
            }
            let f = plan
                .machining_features
                .iter_mut()
                .find(|f| f.id == id)
                .ok_or_else(|| format!("no {id}"))?;
            if (f.shape.z_min, f.shape.z_max) == (z_min, z_max) {
                return Ok(from);
            }
            f.shape.z_min = z_min;
            f.shape.z_max = z_max;
            f.provenance = user_edit("gui.edit.resize", &f.provenance, None);
            Ok(from)
        })
    }

    /// An edit of one operation's cutting conditions, checked against the
    /// machine's limits. Conditions feed only the program: the order (stage
    /// 8) reads tools and constraints, not feeds or speeds, so nothing
    /// before the output is invalidated.
    fn conditions_edit(
        &mut self,
        id: OperationId,
        label: &str,
        f: impl FnOnce(&mut thinplan_plan::Operation, &crate::conditions::Limits) -> Result<(), String>,
    ) -> bool {
        let limits = match (self.plan(), self.knowledge()) {
            (Some(plan), Some(k)) => match plan.operations.iter().find(|o| o.id == id) {
                Some(op) => crate::conditions::limits(plan, k, op),
                None => Err(format!("no {id}")),
            },
            _ => Err("no part open".into()),
        };
        let ok = match limits {
            Ok(l) => self.edit(label, |plan| {
                let op = plan
                    .operations
                    .iter_mut()
                    .find(|o| o.id == id)
                    .ok_or_else(|| format!("no {id}"))?;
                f(op, &l)?;
                Ok(Stage::Output)
            }),
            Err(e) => {
                self.message = format!("{label}: {e}");
                false
            }
        };
        self.refusal = (!ok).then(|| format!("refused: {}", self.message));
        ok
    }

    /// Sets an operation's spindle speed (at most the machine's).
    pub fn set_spindle(&mut self, id: OperationId, rpm: f64) -> bool {
        self.conditions_edit(id, &format!("{id} spindle {rpm:.0}"), |op, l| {
            crate::conditions::set_spindle(op, rpm, l)
        })
    }

    /// Sets the feed (mm/min) of an operation's moves of one kind; its
    /// time is recomputed.
    pub fn set_feed(&mut self, id: OperationId, region: thinplan_plan::Region3, feed: f64) -> bool {
        let name = crate::conditions::region_name(region);
        self.conditions_edit(id, &format!("{id} {name} feed {feed:.0}"), |op, l| {
            crate::conditions::set_feed(op, region, feed, l)
        })
    }

    // ------------------------------------------------------------------
    // Connections

    /// Connects two stiffness features (`base` carries `leaf`, or the two
    /// cross); sequencing and every later stage run again. A feature
    /// connected to itself, an unknown feature, or a pair already
    /// connected (either way round) is refused.
    pub fn add_connection(
        &mut self,
        base: StiffnessFeatureId,
        leaf: StiffnessFeatureId,
        kind: ConnectionKind,
    ) -> bool {
        let word = connection_word(kind);
        let ok = self.edit(&format!("connect {base} {word} {leaf}"), |plan| {
            if !plan.stages_done.contains(&Stage::Recognise) {
                return Err("refused: recognise the stiffness features first".into());
            }
            if base == leaf {
                return Err(format!("refused: {base} cannot be connected to itself"));
            }
            for id in [base, leaf] {
                if !plan.stiffness_features.iter().any(|f| f.id == id) {
                    return Err(format!("refused: there is no stiffness feature {id}"));
                }
            }
            if let Some(c) = plan
                .connections
                .iter()
                .find(|c| (c.base, c.leaf) == (base, leaf) || (c.base, c.leaf) == (leaf, base))
            {
                return Err(format!(
                    "refused: {} and {} are already connected ({} {} {})",
                    base,
                    leaf,
                    c.base,
                    connection_word(c.kind),
                    c.leaf
                ));
            }
            plan.connections.push(Connection {
                base,
                leaf,
                kind,
                provenance: Provenance::new(ProvenanceSource::User, "gui.connection"),
            });
            Ok(Stage::Sequence)
        });
        self.refusal = (!ok).then(|| self.message.clone());
        ok
    }

    /// Removes the connection between `a` and `b` (either way round).
    pub fn remove_connection(&mut self, a: StiffnessFeatureId, b: StiffnessFeatureId) -> bool {
        let ok = self.edit(&format!("disconnect {a} and {b}"), |plan| {
            let i = plan
                .connections
                .iter()
                .position(|c| (c.base, c.leaf) == (a, b) || (c.base, c.leaf) == (b, a))
                .ok_or_else(|| format!("refused: {a} and {b} are not connected"))?;
            plan.connections.remove(i);
            Ok(Stage::Sequence)
        });
        self.refusal = (!ok).then(|| self.message.clone());
        ok
    }

    // ------------------------------------------------------------------
    // Files

    /// Saves the plan (atomic).
    pub fn save_plan(&mut self, path: &Path) -> bool {
        let Some(plan) = self.plan() else {
            return false;
        };
        match thinplan_plan::save(plan, path) {
            Ok(()) => {
                self.message = format!("saved {}", path.display());
                true
            }
            Err(e) => {
                self.message = e.to_string();
                false
            }
        }
    }

    /// Exports the planned program through knowledge's post `post_id`
    /// (the set-up's tool set) and the setup sheet, the same functions
    /// `thinplan plan --gcode --sheet` calls; each file is written
    /// atomically and nothing is written when posting fails.
    pub fn export(&mut self, gcode: &Path, sheet: Option<&Path>, post_id: &str) -> bool {
        match self.try_export(gcode, sheet, post_id) {
            Ok(m) => {
                self.message = m;
                true
            }
            Err(e) => {
                self.message = format!("export: {e}");
                false
            }
        }
    }

    fn try_export(
        &self,
        gcode: &Path,
        sheet: Option<&Path>,
        post_id: &str,
    ) -> Result<String, String> {
        if self.is_running() {
            return Err("a stage is running: export when it ends".into());
        }
        let s = self.session.as_ref().ok_or("no part open")?;
        let plan = &s.plan;
        if !plan.stages_done.contains(&Stage::Verify) {
            return Err("the plan is not verified yet: run all stages first".into());
        }
        let k = &s.knowledge;
        let program = thinplan_pipeline::output::write_program(plan, k, post_id, gcode, None)?;
        let mut m = format!(
            "wrote {} ({} lines, {} tool changes)",
            gcode.display(),
            program.line_count,
            program.tool_changes
        );
        if let Some(path) = sheet {
            thinplan_sheet::write_sheet(path, plan, k, &s.brep, &s.warnings)?;
            m.push_str(&format!(" and {}", path.display()));
        }
        Ok(m)
    }

    /// Opens a saved plan: its part is imported again from its source and
    /// checked against the recorded hash.
    pub fn open_plan(&mut self, path: &Path) -> bool {
        if self.is_running() {
            self.message = "a stage is running: cancel it first".into();
            return false;
        }
        let plan = match thinplan_plan::load(path) {
            Ok(p) => p,
            Err(e) => {
                self.message = e.to_string();
                return false;
            }
        };
        let knowledge = match self.knowledge_for_open() {
            Ok(k) => k,
            Err(e) => {
                self.message = e.message;
                return false;
            }
        };
        match thinplan_import::import(&plan.part.source) {
            Ok(imported) => {
                let mut warnings = imported.warnings;
                if imported.part.sha256 != plan.part.sha256 {
                    warnings.push(format!(
                        "{}: the part file changed since the plan was made",
                        plan.part.source
                    ));
                }
                self.message = format!("opened plan {}", path.display());
                for w in &warnings {
                    self.message.push('\n');
                    self.message.push_str(w);
                }
                self.session = Some(Session {
                    brep: imported.brep,
                    knowledge,
                    plan,
                    warnings: Vec::new(),
                });
                self.after_new_document();
                true
            }
            Err(e) => {
                self.message = format!(
                    "{}: cannot import its part {}: {}",
                    path.display(),
                    plan.part.source,
                    thinplan_pipeline::error_chain(&e)
                );
                false
            }
        }
    }
}

/// How a connection reads between its base and its leaf.
pub fn connection_word(k: ConnectionKind) -> &'static str {
    match k {
        ConnectionKind::BaseLeaf => "carries",
        ConnectionKind::Crossing => "crosses",
    }
}

pub fn kind_word(k: ConstraintKind) -> &'static str {
    match k {
        ConstraintKind::Before => "before",
        ConstraintKind::Simultaneous => "with",
    }
}

fn find_sf(
    plan: &mut Plan,
    id: StiffnessFeatureId,
) -> Result<&mut thinplan_plan::StiffnessFeature, String> {
    plan.stiffness_features
        .iter_mut()
        .find(|f| f.id == id)
        .ok_or_else(|| format!("no {id}"))
}

/// The provenance of a hand edit, naming what it replaced.
fn user_edit(rule: &str, old: &Provenance, was: Option<f64>) -> Provenance {
    let mut p = Provenance::new(ProvenanceSource::User, rule);
    if let Some(w) = was {
        p.values.insert("was".into(), w);
    }
    p.note = if old.source == ProvenanceSource::User {
        old.note.clone()
    } else {
        format!("edited by hand; made by {}", old.rule)
    };
    p
}

/// What differs between two plans, by entity (added or changed).
pub fn changes(before: &Plan, after: &Plan) -> BTreeSet<Entity> {
    let mut out = BTreeSet::new();
    if before.setup != after.setup {
        out.insert(Entity::Setup);
    }
    for f in &after.stiffness_features {
        if before.stiffness_features.iter().find(|b| b.id == f.id) != Some(f) {
            out.insert(Entity::Stiffness(f.id));
        }
    }
    for c in &after.stiffness_constraints {
        if !before.stiffness_constraints.contains(c) {
            out.insert(Entity::Stiffness(c.first));
            out.insert(Entity::Stiffness(c.second));
        }
    }
    // Connections added or removed: both ends changed.
    for (x, y) in [(after, before), (before, after)] {
        for c in &x.connections {
            if !y.connections.contains(c) {
                out.insert(Entity::Stiffness(c.base));
                out.insert(Entity::Stiffness(c.leaf));
            }
        }
    }
    for f in &after.machining_features {
        if before.machining_features.iter().find(|b| b.id == f.id) != Some(f) {
            out.insert(Entity::Machining(f.id));
        }
    }
    for o in &after.operations {
        if before.operations.iter().find(|b| b.id == o.id) != Some(o) {
            out.insert(Entity::Operation(o.id));
        }
    }
    out
}

/// Parses "x, y, z" for the set-up's up direction.
pub fn parse_up(text: &str) -> Result<DVec3, String> {
    thinplan_pipeline::parse_up(text).map_err(|e| e.message)
}
