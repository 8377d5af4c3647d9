//! `thinplan`: the headless driver of the planning stages.
//!
//! A thin shell: it parses arguments, calls the stage crates in pipeline
//! order and prints results. No planning logic lives here.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use thinplan_import::ImportError;
use thinplan_knowledge::Knowledge;
use thinplan_pipeline::{ErrorKind, PipelineError, Session};
use thinplan_plan::{Setup, Stage, Verdict};

mod pocket_cmd;
mod post_cmd;
mod report;
mod simulate_cmd;

/// Exit codes (documented in docs/CLI.md).
mod exit {
    pub const OK: u8 = 0;
    pub const INTERNAL: u8 = 1;
    // 2 is clap's usage error.
    pub const BAD_INPUT: u8 = 3;
    pub const KNOWLEDGE: u8 = 4;
    pub const OUTPUT: u8 = 5;
    /// `simulate`: the stock does not match the part (gouge or missed material).
    pub const NOT_CLEAN: u8 = 6;
    /// `plan`: the verification found the program unsafe; no program written.
    pub const UNSAFE: u8 = 7;
    /// `plan`: the program is safe but leaves material (written).
    pub const INCOMPLETE: u8 = 8;
}

#[derive(Parser)]
#[command(
    name = "thinplan",
    version,
    about = "Process planning for high-speed milling of thin-walled parts"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The set-up, shared by every command that plans: a set-up file and/or flags
/// (a flag overrides the file; the knowledge's defaults fill the rest).
#[derive(clap::Args)]
struct SetupOpts {
    /// Set-up file (RON): `(up: (0.0, 0.0, 1.0), machine: "…", tool_set: "…", material: "…")`,
    /// every field optional.
    #[arg(long)]
    setup: Option<PathBuf>,
    /// The spindle axis in part coordinates, "x,y,z" (default 0,0,1).
    #[arg(long)]
    up: Option<String>,
    /// Machine id (from the knowledge's machines/).
    #[arg(long)]
    machine: Option<String>,
    /// Tool set id (from the knowledge's tools/).
    #[arg(long)]
    tools: Option<String>,
    /// Material id (from the knowledge's materials/).
    #[arg(long)]
    material: Option<String>,
    /// Knowledge directory (default: the knowledge built into thinplan).
    #[arg(long)]
    knowledge: Option<PathBuf>,
}

#[derive(Subcommand)]
enum BenchWhat {
    /// Curvilinear spiral vs parallel offset vs FreeCAD Adaptive on a set of
    /// pockets, all timed with the same feed schedule.
    Pockets {
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum Command {
    /// Read a part (STEP or native .part.ron) and report its B-rep.
    Inspect {
        /// Part file, or builtin:NAME for a bundled sample.
        part: String,
        /// Print one JSON object (the documented contract) instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Plan a part through every stage built so far and write the plan file.
    Plan {
        /// Part file, or builtin:NAME; a bundled sample when omitted.
        part: Option<String>,
        /// Where to write the plan (default: out/NAME.plan.json).
        #[arg(long, short)]
        out: Option<PathBuf>,
        #[command(flatten)]
        setup: SetupOpts,
        /// Machine-readable summary on stdout; no progress output.
        #[arg(long)]
        json: bool,
        /// Also write the NC program (through `--post`).
        #[arg(long)]
        gcode: Option<PathBuf>,
        /// Post-processor id from the knowledge's posts/ (default linuxcnc).
        #[arg(long, default_value = thinplan_knowledge::DEFAULT_POST)]
        post: String,
        /// Also write the LinuxCNC tool table the program needs.
        #[arg(long)]
        tool_table: Option<PathBuf>,
        /// Also write the setup sheet (one self-contained HTML page).
        #[arg(long)]
        sheet: Option<PathBuf>,
        /// Stop after this stage: recognise, sequence, determine, features
        /// (machining features with interference, adjacency and remaining
        /// material), operations or order (the default: every stage).
        #[arg(long)]
        until: Option<String>,
        /// Write per wall a side view of its machining features numbered in
        /// machining order (figure 4.1) as DIR/SFn.svg, and, once there are
        /// operations, its operation layers (figure 7.9) as DIR/SFn.layers.svg.
        #[arg(long, value_name = "DIR")]
        svg: Option<PathBuf>,
        /// List every warning (default: grouped by kind with counts).
        #[arg(long)]
        verbose: bool,
    },
    /// Why the plan is as it is: the provenance of a stiffness feature (SFn),
    /// machining feature (MFn) or operation (OPn) with every constraint and
    /// refusal naming it; with a second id, the chain of constraints that
    /// orders the two.
    Explain {
        /// A plan file written by `thinplan plan`.
        plan: PathBuf,
        id: String,
        /// A second feature: explain the order between the two.
        other: Option<String>,
        #[arg(long)]
        json: bool,
    },
    /// Recognise stiffness features and their connections (stages 2-3).
    Recognize {
        /// Part file, or builtin:NAME.
        part: String,
        #[command(flatten)]
        setup: SetupOpts,
        /// The features and connections as JSON (docs/CLI.md).
        #[arg(long)]
        json: bool,
        /// Write a picture of the part coloured by feature, with the connection graph.
        #[arg(long)]
        svg: Option<PathBuf>,
    },
    /// Load and validate a knowledge directory; list every problem found.
    CheckKnowledge {
        /// The directory (default: the knowledge built into thinplan).
        dir: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// Size a wall's machining features with the sizing model (§4.1.2):
    /// B_RF, h and H that keep the modelled deflection within the allowed value.
    #[command(allow_negative_numbers = true)]
    SizeWall {
        /// Wall length L, mm.
        length: f64,
        /// Final wall thickness t, mm.
        thickness: f64,
        /// Wall height H_w, mm.
        height: f64,
        /// `peripheral` or `face` milling.
        #[arg(long, default_value = "peripheral")]
        mode: String,
        #[arg(long, default_value = thinplan_knowledge::DEFAULT_MATERIAL)]
        material: String,
        #[arg(long)]
        knowledge: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// Benchmarks printed as tables (or JSON rows).
    Bench {
        #[command(subcommand)]
        what: BenchWhat,
    },
    /// Plan one closed pocket with the curvilinear spiral and write it.
    Pocket {
        /// Pocket profile file (see docs/CLI.md).
        profile: PathBuf,
        /// Write a picture of the pocket, the contours and the spiral.
        #[arg(long)]
        svg: Option<PathBuf>,
        /// The spiral as points / arcs with feeds, as JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Write a part (STEP, native or builtin:NAME) as a STEP AP214 file.
    ExportStep { part: String, out: PathBuf },
    /// Score recognition against the MFCAD dataset's per-face labels and
    /// print the per-class table (docs/CLI.md).
    ScoreMfcad {
        /// The MFCAD directory (`*.step` + `*.labels.json`); default: the
        /// external test data (`THINPLAN_DATA`, `../shared/data`, `/work/shared/data`).
        dir: Option<PathBuf>,
        /// Score the depression recogniser alone (no walls).
        #[arg(long)]
        depressions_only: bool,
    },
    /// Write a saved plan's operations as an NC program through a post-processor.
    Post(post_cmd::PostArgs),
    /// Replay an NC program on a Z-map of the blank and compare the stock
    /// with the part (gouges, leftover, air cutting); exit 6 when not clean.
    Simulate(simulate_cmd::SimulateArgs),
    /// Open the desktop application (the `thinplan-gui` binary beside this one).
    Gui {
        /// Part file or builtin:NAME; the bundled sample when omitted.
        part: Option<String>,
    },
    /// List the bundled sample parts.
    Samples,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let json = matches!(
        cli.command,
        Command::Inspect { json: true, .. }
            | Command::Plan { json: true, .. }
            | Command::Explain { json: true, .. }
            | Command::Recognize { json: true, .. }
            | Command::CheckKnowledge { json: true, .. }
            | Command::SizeWall { json: true, .. }
            | Command::Pocket { json: true, .. }
            | Command::Simulate(simulate_cmd::SimulateArgs { json: true, .. })
            | Command::Bench {
                what: BenchWhat::Pockets { json: true }
            }
    );
    let result = std::panic::catch_unwind(|| run(cli.command)).unwrap_or_else(|_| {
        Err(CliError {
            code: exit::INTERNAL,
            kind: "internal",
            message: "internal error (a bug in thinplan; please report it with the input)".into(),
        })
    });
    finish(result, json)
}

fn run(command: Command) -> Result<(), CliError> {
    match command {
        Command::Inspect { part, json } => inspect(&part, json),
        Command::Plan {
            part,
            out,
            setup,
            json,
            gcode,
            post,
            tool_table,
            sheet,
            until,
            svg,
            verbose,
        } => plan(
            part,
            out,
            &setup,
            json,
            Outputs {
                gcode: gcode
                    .as_deref()
                    .map(|g| (g, post.as_str(), tool_table.as_deref())),
                sheet: sheet.as_deref(),
                svg: svg.as_deref(),
                verbose,
            },
            until.as_deref(),
        ),
        Command::Explain {
            plan,
            id,
            other,
            json,
        } => explain(&plan, &id, other.as_deref(), json),
        Command::Recognize {
            part,
            setup,
            json,
            svg,
        } => recognize(&part, &setup, json, svg.as_deref()),
        Command::CheckKnowledge { dir, json } => check_knowledge(dir.as_deref(), json),
        Command::SizeWall {
            length,
            thickness,
            height,
            mode,
            material,
            knowledge,
            json,
        } => size_wall(
            thinplan_sizing::Wall {
                length,
                thickness,
                height,
            },
            &mode,
            &material,
            knowledge.as_deref(),
            json,
        ),
        Command::Bench {
            what: BenchWhat::Pockets { json },
        } => pocket_cmd::bench_pockets(json).map_err(|message| CliError {
            code: exit::INTERNAL,
            kind: "bench",
            message,
        }),
        Command::Pocket { profile, svg, json } => {
            pocket_cmd::pocket(&profile, svg.as_deref(), json).map_err(|message| CliError {
                code: exit::BAD_INPUT,
                kind: "input",
                message,
            })
        }
        Command::ExportStep { part, out } => {
            let imported = thinplan_import::import(&part)?;
            let name = imported
                .part
                .source
                .trim_start_matches("builtin:")
                .to_string();
            let text = thinplan_step::write_step(&imported.brep, &name);
            thinplan_plan::io::write_atomic(&out, text.as_bytes()).map_err(|e| CliError {
                code: exit::OUTPUT,
                kind: "output",
                message: error_chain(&e),
            })?;
            eprintln!("wrote {}", out.display());
            Ok(())
        }
        Command::ScoreMfcad {
            dir,
            depressions_only,
        } => {
            let dir = dir
                .or_else(|| {
                    [
                        std::env::var_os("THINPLAN_DATA").map(PathBuf::from),
                        Some(PathBuf::from("../shared/data")),
                        Some(PathBuf::from("/work/shared/data")),
                    ]
                    .into_iter()
                    .flatten()
                    .map(|d| d.join("mfcad"))
                    .find(|d| d.is_dir())
                })
                .ok_or_else(|| CliError {
                    code: exit::BAD_INPUT,
                    kind: "input",
                    message: "no MFCAD directory given and none found".into(),
                })?;
            let read = |p: &Path| {
                thinplan_step::read_step_file(p)
                    .map(|m| m.brep)
                    .map_err(|e| e.to_string())
            };
            let score = if depressions_only {
                thinplan_recognise::mfcad::score_mfcad_depressions_with(&dir, read)
            } else {
                thinplan_recognise::mfcad::score_mfcad_with(&dir, read)
            };
            for e in &score.errors {
                eprintln!("error: {e}");
            }
            print!("{}", score.table());
            print!("{}", score.confusion_table());
            println!("overall face accuracy: {:.2} %", 100.0 * score.overall());
            Ok(())
        }
        Command::Post(args) => post_cmd::run(&args).map_err(|message| CliError {
            code: exit::BAD_INPUT,
            kind: "post",
            message,
        }),
        Command::Gui { part } => gui(part),
        Command::Simulate(args) => match simulate_cmd::run(&args) {
            Ok(true) => Ok(()),
            Ok(false) => Err(CliError {
                code: exit::NOT_CLEAN,
                kind: "simulate",
                message: String::new(),
            }),
            Err(message) => Err(CliError {
                code: exit::BAD_INPUT,
                kind: "input",
                message,
            }),
        },
        Command::Samples => {
            for (name, _) in thinplan_import::SAMPLES {
                println!("builtin:{name}");
            }
            Ok(())
        }
    }
}

fn finish(result: Result<(), CliError>, json: bool) -> ExitCode {
    match result {
        Ok(()) => ExitCode::from(exit::OK),
        Err(e) => {
            // An empty message means the command already reported its errors.
            if e.message.is_empty() {
            } else if json {
                let v = serde_json::json!({ "error": e.message, "kind": e.kind });
                println!("{v}");
            } else {
                eprintln!("error: {}", e.message);
            }
            ExitCode::from(e.code)
        }
    }
}

struct CliError {
    code: u8,
    kind: &'static str,
    message: String,
}

impl From<ImportError> for CliError {
    fn from(e: ImportError) -> Self {
        CliError {
            code: exit::BAD_INPUT,
            kind: "input",
            message: error_chain(&e),
        }
    }
}

impl From<PipelineError> for CliError {
    fn from(e: PipelineError) -> Self {
        let (code, kind) = match e.kind {
            ErrorKind::Input => (exit::BAD_INPUT, "input"),
            ErrorKind::Knowledge => (exit::KNOWLEDGE, "knowledge"),
            ErrorKind::Setup => (exit::KNOWLEDGE, "setup"),
            ErrorKind::Stage | ErrorKind::Cancelled => (exit::INTERNAL, "stage"),
        };
        CliError {
            code,
            kind,
            message: e.message,
        }
    }
}

fn error_chain(e: &dyn std::error::Error) -> String {
    thinplan_pipeline::error_chain(e)
}

/// The `inspect --json` contract (docs/CLI.md).
#[derive(Serialize)]
struct InspectReport {
    solids: usize,
    faces: usize,
    faces_by_kind: thinplan_brep::FaceKindCounts,
    bbox: [f64; 3],
    volume: f64,
    units: String,
}

fn inspect(part: &str, json: bool) -> Result<(), CliError> {
    let imported = thinplan_import::import(part)?;
    let s = &imported.part.summary;
    let report = InspectReport {
        solids: s.solids,
        faces: s.faces,
        faces_by_kind: imported.brep.face_kind_counts(),
        bbox: s.bbox,
        volume: s.volume,
        units: imported.part.declared_units.clone(),
    };
    if json {
        println!("{}", serde_json::to_string(&report).expect("serialises"));
    } else {
        let k = &report.faces_by_kind;
        println!("part     {part}");
        println!("units    {} (geometry in mm)", report.units);
        println!("solids   {}", report.solids);
        println!(
            "faces    {} (plane {}, cylinder {}, cone {}, sphere {}, torus {}, bspline {}, other {})",
            report.faces, k.plane, k.cylinder, k.cone, k.sphere, k.torus, k.bspline, k.other
        );
        println!(
            "extent   {:.3} x {:.3} x {:.3} mm",
            report.bbox[0], report.bbox[1], report.bbox[2]
        );
        println!("volume   {:.3} mm3", report.volume);
        for w in &imported.warnings {
            println!("warning  {w}");
        }
    }
    Ok(())
}

fn load_knowledge(dir: Option<&Path>) -> Result<Knowledge, CliError> {
    Ok(thinplan_pipeline::load_knowledge(dir)?)
}

fn check_knowledge(dir: Option<&Path>, json: bool) -> Result<(), CliError> {
    let result = match dir {
        Some(d) => Knowledge::load_dir(d),
        None => Knowledge::builtin(),
    };
    match result {
        Ok(k) => {
            if json {
                let v = serde_json::json!({
                    "origin": k.origin,
                    "machines": k.machines.keys().collect::<Vec<_>>(),
                    "tool_sets": k.tool_sets.keys().collect::<Vec<_>>(),
                    "materials": k.materials.keys().collect::<Vec<_>>(),
                    "errors": [],
                });
                println!("{v}");
            } else {
                println!(
                    "{}: ok ({} machine(s), {} tool set(s), {} material(s))",
                    k.origin,
                    k.machines.len(),
                    k.tool_sets.len(),
                    k.materials.len()
                );
            }
            Ok(())
        }
        Err(errors) => {
            if json {
                let list: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
                println!("{}", serde_json::json!({ "errors": list }));
            } else {
                for e in errors {
                    eprintln!("{:?}", miette::Report::new(e));
                }
            }
            Err(CliError {
                code: exit::KNOWLEDGE,
                kind: "knowledge",
                message: String::new(),
            })
        }
    }
}

/// The set-up the options ask for, checked against the knowledge.
fn make_setup(opts: &SetupOpts, k: &Knowledge) -> Result<Setup, CliError> {
    let req = thinplan_pipeline::SetupRequest {
        setup_file: opts.setup.clone(),
        up: opts
            .up
            .as_deref()
            .map(thinplan_pipeline::parse_up)
            .transpose()?,
        machine: opts.machine.clone(),
        tool_set: opts.tools.clone(),
        material: opts.material.clone(),
    };
    Ok(thinplan_pipeline::make_setup(&req, k)?)
}

/// What `plan` writes besides the plan file.
struct Outputs<'a> {
    /// Program, post-processor id and tool table.
    gcode: Option<(&'a Path, &'a str, Option<&'a Path>)>,
    sheet: Option<&'a Path>,
    /// Directory for the per-wall pictures.
    svg: Option<&'a Path>,
    /// Every warning, not grouped.
    verbose: bool,
}

fn plan(
    part: Option<String>,
    out: Option<PathBuf>,
    setup_opts: &SetupOpts,
    json: bool,
    outputs: Outputs<'_>,
    until: Option<&str>,
) -> Result<(), CliError> {
    let Outputs {
        gcode,
        sheet,
        svg,
        verbose,
    } = outputs;
    let last = match until {
        None => thinplan_pipeline::LAST_BUILT,
        Some(name) => stage_named(name)?,
    };
    if gcode.is_some() && last < Stage::Verify {
        return Err(CliError {
            code: exit::BAD_INPUT,
            kind: "input",
            message: format!(
                "--gcode needs every stage; --until {} stops before the verification",
                until.unwrap_or_default()
            ),
        });
    }
    let source = part.unwrap_or_else(|| format!("builtin:{}", thinplan_import::DEFAULT_SAMPLE));
    let knowledge = load_knowledge(setup_opts.knowledge.as_deref())?;
    // Validate the set-up before the (possibly long) import.
    let setup = make_setup(setup_opts, &knowledge)?;
    let progress = if json {
        ProgressBar::hidden()
    } else {
        // Draws only when stderr is a terminal.
        ProgressBar::new(1 + thinplan_pipeline::PLANNING_STAGES.len() as u64).with_style(
            ProgressStyle::with_template("{spinner} [{pos}/{len}] {msg}").expect("valid template"),
        )
    };
    progress.set_message(format!("import {source}"));
    let started = std::time::Instant::now();
    let mut session = Session::open(&source, setup, knowledge)?;
    progress.inc(1);
    // Wall time per stage, for `--verbose` on stderr only: the plan and the
    // JSON stay byte-identical between runs.
    let mut times = vec![("import".to_string(), started)];
    session.run_to(last, &std::sync::atomic::AtomicBool::new(false), |stage| {
        progress.inc(1);
        let name = format!("{stage:?}").to_lowercase();
        progress.set_message(name.clone());
        times.push((name, std::time::Instant::now()));
    })?;
    progress.finish_and_clear();
    if verbose {
        eprint!("{}", report::stage_times(&times, std::time::Instant::now()));
    }
    let Session {
        plan,
        warnings,
        brep,
        knowledge,
    } = session;

    // With no output named, the whole job goes to a folder of its own:
    // plan, program, tool table and sheet.
    let default_job = out.is_none()
        && gcode.is_none()
        && sheet.is_none()
        && last == thinplan_pipeline::LAST_BUILT;
    let (dir, stem) = default_dir(&source);
    let job_program = dir.join(format!("{stem}.ngc"));
    let job_table = dir.join(format!("{stem}.tbl"));
    let job_sheet = dir.join(format!("{stem}.sheet.html"));
    let (gcode, sheet) = if default_job {
        let post = thinplan_knowledge::DEFAULT_POST;
        (
            Some((job_program.as_path(), post, Some(job_table.as_path()))),
            Some(job_sheet.as_path()),
        )
    } else {
        (gcode, sheet)
    };
    let out = out.unwrap_or_else(|| dir.join(format!("{stem}.plan.json")));
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| CliError {
            code: exit::OUTPUT,
            kind: "output",
            message: format!("{}: cannot create directory: {e}", dir.display()),
        })?;
    }
    thinplan_plan::save(&plan, &out).map_err(|e| CliError {
        code: exit::OUTPUT,
        kind: "output",
        message: error_chain(&e),
    })?;
    let plan_file = out.display().to_string();
    let verdict = plan.verification.as_ref().map(|v| v.verdict);
    let mut program_written = None;
    if let Some((path, post, table)) = gcode {
        if verdict == Some(Verdict::Unsafe) || plan.operation_order.is_empty() {
            // A stale program from an earlier run must not pass for this one.
            for p in std::iter::once(path).chain(table) {
                if p.is_file() {
                    let _ = std::fs::remove_file(p);
                }
            }
        } else {
            post_cmd::write_program(&plan, &knowledge, post, path, table).map_err(|message| {
                CliError {
                    code: exit::OUTPUT,
                    kind: "output",
                    message,
                }
            })?;
            program_written = Some(path.display().to_string());
        }
    }
    if let Some(path) = sheet {
        thinplan_sheet::write_sheet(path, &plan, &knowledge, &brep, &warnings).map_err(
            |message| CliError {
                code: exit::OUTPUT,
                kind: "output",
                message,
            },
        )?;
    }
    let pictures = match svg {
        Some(dir) => wall_pictures(&plan, dir)?,
        None => Vec::new(),
    };
    if json {
        let mut v = thinplan_pipeline::report::plan_json(&plan, &brep, &plan_file, &warnings);
        v["collisions"] = thinplan_collision::collisions_json(&thinplan_collision::check_holders(
            &plan, &knowledge, &brep,
        ));
        v["program"] = serde_json::json!(program_written);
        if svg.is_some() {
            v["pictures"] = serde_json::json!(pictures);
        }
        println!("{v}");
    } else {
        print!(
            "{}",
            report::summary(&source, &plan, &knowledge, &warnings, verbose)
        );
        if let Some(dir) = svg {
            println!("{} picture(s) written to {}", pictures.len(), dir.display());
        }
        println!("plan written to {plan_file}");
        match (&program_written, gcode) {
            (Some(p), _) => println!("program written to {p}"),
            (None, Some((p, _, _))) => println!("program NOT written to {}", p.display()),
            _ => {}
        }
    }
    // The verdict is the exit code (docs/CLI.md): a driver in CI must not
    // mistake an unsafe or incomplete plan for a finished one.
    match verdict {
        Some(Verdict::Unsafe) => Err(CliError {
            code: exit::UNSAFE,
            kind: "unsafe",
            message: String::new(),
        }),
        Some(Verdict::Incomplete) => Err(CliError {
            code: exit::INCOMPLETE,
            kind: "incomplete",
            message: String::new(),
        }),
        _ => Ok(()),
    }
}

/// The stage `--until` names (`features`: machining features complete,
/// stage 6).
fn stage_named(name: &str) -> Result<Stage, CliError> {
    let stage = match name.to_ascii_lowercase().as_str() {
        "recognise" | "recognize" | "connect" => Stage::Connect,
        "sequence" => Stage::Sequence,
        "determine" => Stage::Determine,
        "features" | "resolve" => Stage::Resolve,
        "operations" => Stage::Operations,
        "order" => Stage::Order,
        "verify" => Stage::Verify,
        _ => {
            return Err(CliError {
                code: exit::BAD_INPUT,
                kind: "input",
                message: format!(
                    "--until {name}: not a stage; use recognise, sequence, determine, features, \
                     operations, order or verify"
                ),
            })
        }
    };
    Ok(stage)
}

/// Per wall with machining features, figure 4.1's side view (and figure
/// 7.9's layers once there are operations), written into `dir`.
fn wall_pictures(plan: &thinplan_plan::Plan, dir: &Path) -> Result<Vec<String>, CliError> {
    let fail = |path: &Path, e: std::io::Error| CliError {
        code: exit::OUTPUT,
        kind: "output",
        message: format!("{}: {e}", path.display()),
    };
    std::fs::create_dir_all(dir).map_err(|e| fail(dir, e))?;
    let mut written = Vec::new();
    for sf in plan
        .stiffness_features
        .iter()
        .filter(|sf| sf.kind == thinplan_plan::StiffnessKind::Wall)
        .filter(|sf| plan.machining_features.iter().any(|m| m.owner == sf.id))
    {
        let mut pictures = vec![(
            dir.join(format!("{}.svg", sf.id)),
            thinplan_sheet::wall_steps_svg(plan, sf.id),
        )];
        if !plan.operations.is_empty() {
            pictures.push((
                dir.join(format!("{}.layers.svg", sf.id)),
                thinplan_sheet::layers_svg(plan, sf.id),
            ));
        }
        for (path, text) in pictures {
            std::fs::write(&path, text).map_err(|e| fail(&path, e))?;
            written.push(path.display().to_string());
        }
    }
    Ok(written)
}

fn explain(plan_file: &Path, id: &str, other: Option<&str>, json: bool) -> Result<(), CliError> {
    let plan = thinplan_plan::load(plan_file).map_err(|e| CliError {
        code: exit::BAD_INPUT,
        kind: "input",
        message: error_chain(&e),
    })?;
    let usage = |message: String| CliError {
        code: exit::BAD_INPUT,
        kind: "input",
        message: format!("{}: {message}", plan_file.display()),
    };
    let a = thinplan_pipeline::explain::parse_subject(&plan, id).map_err(usage)?;
    let v = match other {
        None => thinplan_pipeline::explain::explain(&plan, a),
        Some(b) => {
            let b = thinplan_pipeline::explain::parse_subject(&plan, b).map_err(usage)?;
            thinplan_pipeline::explain::explain_pair(&plan, a, b).map_err(usage)?
        }
    };
    if json {
        println!("{v}");
    } else {
        print!("{}", thinplan_pipeline::explain::explain_text(&v));
    }
    Ok(())
}

/// Runs the GUI binary that is built beside this one; the CLI stays free of
/// the GUI's dependencies.
fn gui(part: Option<String>) -> Result<(), CliError> {
    let exe = std::env::current_exe().map_err(|e| CliError {
        code: exit::INTERNAL,
        kind: "gui",
        message: format!("cannot find this program's path: {e}"),
    })?;
    let gui = exe.with_file_name(format!("thinplan-gui{}", std::env::consts::EXE_SUFFIX));
    if !gui.is_file() {
        return Err(CliError {
            code: exit::INTERNAL,
            kind: "gui",
            message: format!(
                "{} is not built: run `cargo build --release -p thinplan-gui` (or `cargo run -p thinplan-gui`)",
                gui.display()
            ),
        });
    }
    let status = std::process::Command::new(&gui)
        .args(part)
        .status()
        .map_err(|e| CliError {
            code: exit::INTERNAL,
            kind: "gui",
            message: format!("{}: {e}", gui.display()),
        })?;
    if status.success() {
        Ok(())
    } else {
        Err(CliError {
            code: exit::INTERNAL,
            kind: "gui",
            message: format!("{} exited with {status}", gui.display()),
        })
    }
}

/// The folder a plan's default outputs go to, and their stem:
/// `out/NAME-HASH/` where HASH comes from the part's full path (two parts
/// of one name in different folders never share a folder), or
/// `out/builtin-NAME/` for a bundled sample.
fn default_dir(source: &str) -> (PathBuf, String) {
    if let Some(name) = source.strip_prefix("builtin:") {
        return (
            PathBuf::from("out").join(format!("builtin-{name}")),
            name.to_string(),
        );
    }
    let path = Path::new(source);
    let stem = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .and_then(|n| n.split('.').next().map(str::to_string))
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "part".into());
    let full = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    // FNV-1a: a stable name, not a security measure.
    let hash = full
        .to_string_lossy()
        .bytes()
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
            (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
        });
    (
        PathBuf::from("out").join(format!("{stem}-{:08x}", hash >> 32)),
        stem,
    )
}

fn size_wall(
    wall: thinplan_sizing::Wall,
    mode: &str,
    material: &str,
    knowledge_dir: Option<&Path>,
    json: bool,
) -> Result<(), CliError> {
    let k = load_knowledge(knowledge_dir)?;
    let mode = match mode {
        "peripheral" => thinplan_sizing::MillingMode::Peripheral,
        "face" => thinplan_sizing::MillingMode::Face,
        other => {
            return Err(CliError {
                code: exit::BAD_INPUT,
                kind: "input",
                message: format!("--mode `{other}`: expected `peripheral` or `face`"),
            })
        }
    };
    let m = k.material(material).ok_or_else(|| CliError {
        code: exit::KNOWLEDGE,
        kind: "knowledge",
        message: format!("no material `{material}` in {}", k.origin),
    })?;
    let sized =
        thinplan_sizing::size_wall(&wall, &k.sizing, m.youngs_modulus, mode).map_err(|e| {
            CliError {
                code: exit::BAD_INPUT,
                kind: "sizing",
                message: e.to_string(),
            }
        })?;
    if json {
        let provenance: std::collections::BTreeMap<&str, f64> = sized
            .provenance
            .iter()
            .map(|(n, v)| (n.as_str(), *v))
            .collect();
        let v = serde_json::json!({
            "wall": {"length": wall.length, "thickness": wall.thickness, "height": wall.height},
            "mode": mode.name(),
            "material": material,
            "b_rf": sized.b_rf,
            "h": sized.h,
            "big_h": sized.big_h,
            "deflection": sized.deflection,
            "allowed_deflection": k.sizing.allowed_deflection,
            "iterations": sized.iterations,
            "provenance": provenance,
        });
        println!("{v}");
    } else {
        println!(
            "wall {}x{}x{} mm, {} milling, {}:",
            wall.length,
            wall.thickness,
            wall.height,
            mode.name(),
            material
        );
        println!(
            "  B_RF {:.2} mm, h {:.2} mm, H {:.2} mm; deflection {:.4} mm (allowed {} mm)",
            sized.b_rf, sized.h, sized.big_h, sized.deflection, k.sizing.allowed_deflection
        );
    }
    Ok(())
}

fn recognize(
    source: &str,
    setup_opts: &SetupOpts,
    json: bool,
    svg: Option<&Path>,
) -> Result<(), CliError> {
    let knowledge = load_knowledge(setup_opts.knowledge.as_deref())?;
    let setup = make_setup(setup_opts, &knowledge)?;
    let imported = thinplan_import::import(source)?;
    let machine = knowledge
        .machine(&setup.machine)
        .expect("checked in make_setup");
    let r = thinplan_recognise::recognise(&imported.brep, setup.up, &knowledge, machine);
    if let Some(path) = svg {
        let picture = thinplan_recognise::report::to_svg(&r, &imported.brep);
        thinplan_plan::io::write_atomic(path, picture.as_bytes()).map_err(|e| CliError {
            code: exit::OUTPUT,
            kind: "output",
            message: error_chain(&e),
        })?;
    }
    if json {
        println!(
            "{}",
            thinplan_recognise::report::to_json(&r, &imported.brep)
        );
    } else {
        println!(
            "{} stiffness feature(s), {} connection(s)",
            r.features.len(),
            r.connections.len()
        );
        for f in &r.features {
            let role = f
                .role
                .map(thinplan_recognise::report::role_name)
                .unwrap_or("");
            let t = f
                .thickness
                .map(|t| format!(" t={t:.3}"))
                .unwrap_or_default();
            let d = f.diameter.map(|d| format!(" d={d:.3}")).unwrap_or_default();
            println!(
                "  {} {} {}{}{} h={:.3} l={:.3} faces={:?}",
                f.id,
                thinplan_recognise::report::kind_name(f.kind),
                role,
                t,
                d,
                f.height,
                f.length,
                f.faces
            );
        }
        for c in &r.connections {
            let kind = match c.kind {
                thinplan_plan::ConnectionKind::BaseLeaf => "base-leaf",
                thinplan_plan::ConnectionKind::Crossing => "crossing",
            };
            println!("  {} -> {} {kind}", c.base, c.leaf);
        }
        for w in &r.warnings {
            println!("warning: {w}");
        }
    }
    Ok(())
}
