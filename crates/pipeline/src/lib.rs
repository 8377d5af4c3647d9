//! The planning stages in pipeline order, as one session that the CLI and
//! the GUI drive the same way (DESIGN.md, "The pipeline").
//!
//! A [`Session`] owns the imported part (its B-rep, which the plan only
//! references), the knowledge and the plan. [`Session::run_stage`] runs the
//! next stage as a function of the plan so far plus the knowledge;
//! [`Session::run_to`] runs several with progress and cancellation. No stage
//! logic lives here: each stage is its own crate.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;
use thinplan_brep::Brep;
use thinplan_import::ImportedPart;
use thinplan_knowledge::Knowledge;
use thinplan_plan::{Plan, Provenance, ProvenanceSource, Setup, Stage};

pub mod explain;
pub mod output;
pub mod report;

/// Why a session could not go on; `kind` tells a driver which exit code or
/// message style fits.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct PipelineError {
    pub kind: ErrorKind,
    pub message: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// Bad user input: part file, set-up file, option values.
    Input,
    /// Knowledge that does not load or lacks what the set-up names.
    Knowledge,
    /// A set-up the machine cannot do.
    Setup,
    /// A stage failed (a bug or an unsupported case).
    Stage,
    /// Cancelled by the driver.
    Cancelled,
}

impl PipelineError {
    fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        PipelineError {
            kind,
            message: message.into(),
        }
    }
}

/// Loads the knowledge directory, or the built-in copy; every problem in one message.
pub fn load_knowledge(dir: Option<&Path>) -> Result<Knowledge, PipelineError> {
    let result = match dir {
        Some(d) => Knowledge::load_dir(d),
        None => Knowledge::builtin(),
    };
    result.map_err(|errors| {
        PipelineError::new(
            ErrorKind::Knowledge,
            errors
                .iter()
                .map(|e| e.to_string())
                .collect::<Vec<_>>()
                .join("\n"),
        )
    })
}

/// What a user asks of a set-up: a set-up file and/or explicit choices (an
/// explicit choice overrides the file; the knowledge's defaults fill the rest).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SetupRequest {
    pub setup_file: Option<PathBuf>,
    pub up: Option<DVec3>,
    pub machine: Option<String>,
    pub tool_set: Option<String>,
    pub material: Option<String>,
}

/// A set-up file: every field optional.
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SetupFile {
    up: Option<(f64, f64, f64)>,
    machine: Option<String>,
    tool_set: Option<String>,
    material: Option<String>,
}

/// Parses "x,y,z" into a unit vector.
pub fn parse_up(text: &str) -> Result<DVec3, PipelineError> {
    let bad = || {
        PipelineError::new(
            ErrorKind::Input,
            format!("--up `{text}`: expected three numbers x,y,z, not all zero"),
        )
    };
    let v: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        return Err(bad());
    }
    DVec3::new(v[0], v[1], v[2]).try_normalize().ok_or_else(bad)
}

/// Stage 1's choices checked against the knowledge: the resources exist.
pub fn make_setup(req: &SetupRequest, k: &Knowledge) -> Result<Setup, PipelineError> {
    let file: SetupFile = match &req.setup_file {
        Some(path) => thinplan_knowledge::load_ron(path)
            .map_err(|e| PipelineError::new(ErrorKind::Input, e.to_string()))?,
        None => SetupFile::default(),
    };
    let up = match (req.up, file.up) {
        (Some(up), _) => up
            .try_normalize()
            .ok_or_else(|| PipelineError::new(ErrorKind::Input, "set-up: up is a zero vector"))?,
        (None, Some((x, y, z))) => parse_up(&format!("{x},{y},{z}")).map_err(|e| {
            PipelineError::new(
                ErrorKind::Input,
                format!(
                    "{}: up: {}",
                    req.setup_file.as_deref().unwrap_or(Path::new("")).display(),
                    e.message
                ),
            )
        })?,
        (None, None) => DVec3::Z,
    };
    let machine = req
        .machine
        .clone()
        .or(file.machine)
        .unwrap_or_else(|| thinplan_knowledge::DEFAULT_MACHINE.into());
    let tool_set = req
        .tool_set
        .clone()
        .or(file.tool_set)
        .unwrap_or_else(|| thinplan_knowledge::DEFAULT_TOOL_SET.into());
    let material = req
        .material
        .clone()
        .or(file.material)
        .unwrap_or_else(|| thinplan_knowledge::DEFAULT_MATERIAL.into());
    let missing = |what: &str, id: &str, known: Vec<&String>| {
        PipelineError::new(
            ErrorKind::Knowledge,
            format!(
                "set-up: no {what} `{id}` in {} (known: {})",
                k.origin,
                known
                    .iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
    };
    k.machine(&machine)
        .ok_or_else(|| missing("machine", &machine, k.machines.keys().collect()))?;
    k.tool_set(&tool_set)
        .ok_or_else(|| missing("tool set", &tool_set, k.tool_sets.keys().collect()))?;
    k.material(&material)
        .ok_or_else(|| missing("material", &material, k.materials.keys().collect()))?;
    Ok(Setup {
        up,
        machine,
        tool_set,
        material,
        provenance: Provenance::new(
            ProvenanceSource::User,
            if req.setup_file.is_some() {
                "cli.setup_file"
            } else {
                "cli.setup"
            },
        )
        .with_value("up_x", up.x)
        .with_value("up_y", up.y)
        .with_value("up_z", up.z),
    })
}

/// An impossible set-up is refused: the part, placed with `up` along the
/// machine's z, must fit in the axis travel (checked on the corners of its
/// box, which over-estimates a rotated part slightly: the safe side).
pub fn check_fits(
    part: &thinplan_plan::PartRef,
    setup: &Setup,
    k: &Knowledge,
) -> Result<(), PipelineError> {
    let m = k.machine(&setup.machine).ok_or_else(|| {
        PipelineError::new(
            ErrorKind::Knowledge,
            format!("set-up: no machine `{}`", setup.machine),
        )
    })?;
    let frame = thinplan_brep::Frame::from_axis_ref(DVec3::ZERO, setup.up, None);
    let b = part.summary.bbox;
    let mut ext = [0.0f64; 3];
    for (i, axis) in [frame.x, frame.y, frame.z].iter().enumerate() {
        ext[i] = b[0] * axis.x.abs() + b[1] * axis.y.abs() + b[2] * axis.z.abs();
    }
    for (i, (name, a)) in [("x", &m.x), ("y", &m.y), ("z", &m.z)].iter().enumerate() {
        let travel = a.travel.1 - a.travel.0;
        if ext[i] > travel {
            return Err(PipelineError::new(
                ErrorKind::Setup,
                format!(
                    "impossible set-up: the part is {:.1} mm along machine {name} but machine `{}` travels {:.1} mm",
                    ext[i], m.id, travel
                ),
            ));
        }
    }
    Ok(())
}

/// The stages a session runs after import and set-up, in order.
pub const PLANNING_STAGES: [Stage; 7] = [
    Stage::Recognise,
    Stage::Sequence,
    Stage::Determine,
    Stage::Resolve,
    Stage::Operations,
    Stage::Order,
    Stage::Verify,
];

/// A part being planned: its geometry, the knowledge and the plan so far.
pub struct Session {
    pub brep: Brep,
    pub knowledge: Knowledge,
    pub plan: Plan,
    /// Warnings of import and of every stage run, in order.
    pub warnings: Vec<String>,
}

impl Session {
    /// Stages 0 and 1: imports `source` (a file or `builtin:NAME`) and
    /// places it by `setup` (already checked against `knowledge` by
    /// [`make_setup`]).
    pub fn open(
        source: &str,
        setup: Setup,
        knowledge: Knowledge,
    ) -> Result<Session, PipelineError> {
        let ImportedPart {
            part,
            brep,
            warnings,
        } = thinplan_import::import(source)
            .map_err(|e| PipelineError::new(ErrorKind::Input, error_chain(&e)))?;
        check_fits(&part, &setup, &knowledge)?;
        let mut plan = Plan::new(part, setup);
        plan.notes
            .insert("knowledge".into(), knowledge.origin.clone());
        plan.notes
            .insert("thinplan_version".into(), env!("CARGO_PKG_VERSION").into());
        Ok(Session {
            brep,
            knowledge,
            plan,
            warnings,
        })
    }

    /// The next stage the plan needs, or `None` when every planning stage is done.
    pub fn next_stage(&self) -> Option<Stage> {
        PLANNING_STAGES
            .iter()
            .copied()
            .find(|s| !self.plan.stages_done.contains(s))
    }

    /// Runs one stage on the plan so far (dropping that stage's and later
    /// results first). Recognise also runs Connect: they share one pass.
    pub fn run_stage(&mut self, stage: Stage) -> Result<(), PipelineError> {
        let needs = |s: Stage| -> Result<(), PipelineError> {
            if self.plan.stages_done.contains(&s) {
                Ok(())
            } else {
                Err(PipelineError::new(
                    ErrorKind::Stage,
                    format!("{stage:?} needs {s:?} to have run"),
                ))
            }
        };
        match stage {
            Stage::Import | Stage::Setup => Ok(()),
            Stage::Recognise | Stage::Connect => {
                needs(Stage::Setup)?;
                self.plan.invalidate_from(Stage::Recognise);
                let machine = self
                    .knowledge
                    .machine(&self.plan.setup.machine)
                    .ok_or_else(|| {
                        PipelineError::new(
                            ErrorKind::Knowledge,
                            format!("set-up: no machine `{}`", self.plan.setup.machine),
                        )
                    })?;
                let r = thinplan_recognise::recognise(
                    &self.brep,
                    self.plan.setup.up,
                    &self.knowledge,
                    machine,
                );
                self.plan.stiffness_features = r.features;
                self.plan.connections = r.connections;
                self.plan
                    .stages_done
                    .extend([Stage::Recognise, Stage::Connect]);
                self.warnings.extend(r.warnings);
                Ok(())
            }
            Stage::Sequence => {
                needs(Stage::Connect)?;
                thinplan_sequence::run(&self.plan, &self.knowledge).apply_to(&mut self.plan);
                Ok(())
            }
            Stage::Determine => {
                needs(Stage::Sequence)?;
                let d = thinplan_determine::determine(&self.plan, &self.brep, &self.knowledge)
                    .map_err(|e| PipelineError::new(ErrorKind::Stage, e.to_string()))?;
                self.warnings.extend(d.warnings.iter().cloned());
                d.apply_to(&mut self.plan);
                Ok(())
            }
            Stage::Resolve => {
                needs(Stage::Determine)?;
                let r = thinplan_resolve::resolve(&self.plan, &self.brep, &self.knowledge)
                    .map_err(|e| PipelineError::new(ErrorKind::Stage, e.to_string()))?;
                self.warnings.extend(r.warnings.iter().cloned());
                r.apply_to(&mut self.plan);
                Ok(())
            }
            Stage::Operations => {
                needs(Stage::Resolve)?;
                let ops = thinplan_operations::operations(&self.plan, &self.knowledge)
                    .map_err(|e| PipelineError::new(ErrorKind::Stage, e.to_string()))?;
                self.warnings.extend(ops.warnings.iter().cloned());
                ops.apply_to(&mut self.plan);
                Ok(())
            }
            Stage::Order => {
                needs(Stage::Operations)?;
                let order = thinplan_operations::order(&self.plan, &self.knowledge)
                    .map_err(|e| PipelineError::new(ErrorKind::Stage, e.to_string()))?;
                thinplan_operations::order::apply_order(&mut self.plan, order);
                let b = self.brep.bbox();
                let links = thinplan_operations::links::lower_links(
                    &mut self.plan,
                    &self.knowledge,
                    (b.min, b.max),
                )
                .map_err(|e| PipelineError::new(ErrorKind::Stage, e.to_string()))?;
                if !links.skipped.is_empty() {
                    self.warnings.push(format!(
                        "links: {} operation(s) not followed on the in-process stock (tool axis not the \
                         set-up's up, or tool not in the set); their links stay over the stock's top",
                        links.skipped.len()
                    ));
                }
                Ok(())
            }
            Stage::Verify => {
                needs(Stage::Order)?;
                thinplan_verify::verify(&mut self.plan, &self.brep, &self.knowledge)
                    .map_err(|e| PipelineError::new(ErrorKind::Stage, e.to_string()))?;
                Ok(())
            }
            Stage::Output => Err(PipelineError::new(
                ErrorKind::Stage,
                format!("{stage:?} is not built yet"),
            )),
        }
    }

    /// Runs the stages the plan still needs up to and including `last`,
    /// calling `progress` before each; stops between stages when `cancel`
    /// is set.
    pub fn run_to(
        &mut self,
        last: Stage,
        cancel: &AtomicBool,
        mut progress: impl FnMut(Stage),
    ) -> Result<(), PipelineError> {
        while let Some(stage) = self.next_stage().filter(|s| *s <= last) {
            if cancel.load(Ordering::Relaxed) {
                return Err(PipelineError::new(ErrorKind::Cancelled, "cancelled"));
            }
            progress(stage);
            self.run_stage(stage)?;
        }
        Ok(())
    }

    /// Runs every planning stage that is built.
    pub fn run_all(&mut self, progress: impl FnMut(Stage)) -> Result<(), PipelineError> {
        self.run_to(LAST_BUILT, &AtomicBool::new(false), progress)
    }
}

/// The last stage this build can run.
pub const LAST_BUILT: Stage = Stage::Verify;

/// An error with its sources, on one line.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(inner) = src {
        let t = inner.to_string();
        if !s.contains(&t) {
            s.push_str(": ");
            s.push_str(&t);
        }
        src = inner.source();
    }
    s
}
