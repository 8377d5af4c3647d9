//! `thinplan post PLAN`: writes a saved plan's operations as an NC program
//! through a post-processor from knowledge; a thin driver of `thinplan-post`.
//! The writing itself is `thinplan_pipeline::output::write_program`, which
//! `thinplan plan --gcode` and the GUI's export also call.

use std::path::PathBuf;

use thinplan_knowledge::{Knowledge, DEFAULT_POST};
pub use thinplan_pipeline::output::{post_of, write_program};

#[derive(clap::Args, Debug, Clone)]
pub struct PostArgs {
    /// A saved plan file (with operations).
    pub plan: PathBuf,
    /// Post-processor id from the knowledge's `posts/` (e.g. linuxcnc, fanuc).
    #[arg(long = "post", default_value = DEFAULT_POST)]
    pub post: String,
    /// The NC program to write; default: the plan's path with the post's
    /// extension (`part.plan.ron` → `part.plan.ngc`).
    #[arg(short = 'o', long = "out")]
    pub out: Option<PathBuf>,
    /// Also write the LinuxCNC tool table (`.tbl`) the program's tool numbers refer to.
    #[arg(long = "tool-table")]
    pub tool_table: Option<PathBuf>,
    /// Knowledge directory (default: the built-in copy).
    #[arg(long)]
    pub knowledge: Option<PathBuf>,
}

/// Loads the plan and knowledge, posts, writes, and prints a one-line summary.
pub fn run(args: &PostArgs) -> Result<(), String> {
    let plan = thinplan_plan::load(&args.plan).map_err(|e| e.to_string())?;
    let knowledge = match &args.knowledge {
        Some(d) => Knowledge::load_dir(d),
        None => Knowledge::builtin(),
    }
    .map_err(|errors| {
        errors
            .iter()
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
            .join("\n")
    })?;
    // The plan describes the part it was made from: a changed part file
    // would get a program for another part.
    let part = thinplan_import::import(&plan.part.source).map_err(|e| {
        format!(
            "{}: cannot read the plan's part {} to check it has not changed: {e}",
            args.plan.display(),
            plan.part.source
        )
    })?;
    if part.part.sha256 != plan.part.sha256 {
        return Err(format!(
            "{}: the part {} changed since the plan was made (SHA-256 {} in the plan, {} now); \
             plan it again",
            args.plan.display(),
            plan.part.source,
            &plan.part.sha256[..plan.part.sha256.len().min(16)],
            &part.part.sha256[..16]
        ));
    }
    let out = match &args.out {
        Some(o) => o.clone(),
        None => {
            let ext = &post_of(&knowledge, &args.post)?.extension;
            args.plan.with_extension(ext)
        }
    };
    let p = write_program(
        &plan,
        &knowledge,
        &args.post,
        &out,
        args.tool_table.as_deref(),
    )?;
    println!(
        "{}: {} lines, {} tool change(s), {} arc(s), feed {:.1} mm, rapid {:.1} mm (post {})",
        out.display(),
        p.line_count,
        p.tool_changes,
        p.arc_count,
        p.feed_length_mm,
        p.rapid_length_mm,
        args.post
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use thinplan_plan::*;

    fn plan_with_one_operation() -> Plan {
        let part = PartRef {
            source: "builtin:tall_rib".into(),
            format: PartFormat::Native,
            sha256: thinplan_import::import("builtin:tall_rib")
                .unwrap()
                .part
                .sha256,
            declared_units: "mm".into(),
            summary: PartSummary {
                solids: 1,
                faces: 6,
                bbox: [10.0, 10.0, 10.0],
                volume: 1000.0,
            },
        };
        let setup = Setup {
            up: DVec3::Z,
            machine: "hsm_5axis".into(),
            tool_set: "endmills_12_20".into(),
            material: "al7075".into(),
            provenance: Provenance::new(ProvenanceSource::Default, "test"),
        };
        let mut plan = Plan::new(part, setup);
        plan.operations.push(Operation {
            id: OperationId(1),
            feature: MachiningFeatureId(1),
            method: "test".into(),
            tool: "em12".into(),
            tool_axis: DVec3::Z,
            spindle_rpm: 10000.0,
            start: DVec3::new(0.0, 0.0, 2.0),
            moves: vec![PathMove {
                to: DVec3::new(10.0, 0.0, -1.0),
                arc: None,
                feed: 500.0,
                region: Region3::Rest,
            }],
            schedule: Default::default(),
            provenance: Provenance::new(ProvenanceSource::Default, "test"),
            link_z: None,
        });
        plan
    }

    #[test]
    fn run_writes_the_program_and_the_tool_table() {
        let dir = std::env::temp_dir().join(format!("thinplan-post-cmd-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plan_path = dir.join("part.plan.ron");
        thinplan_plan::save(&plan_with_one_operation(), &plan_path).unwrap();
        let args = PostArgs {
            plan: plan_path.clone(),
            post: "fanuc".into(),
            out: None,
            tool_table: Some(dir.join("tools.tbl")),
            knowledge: None,
        };
        run(&args).unwrap();
        let text = std::fs::read_to_string(dir.join("part.plan.nc")).unwrap();
        assert!(text.starts_with("%\nO0001\n"), "{text}");
        assert!(std::fs::read_to_string(dir.join("tools.tbl"))
            .unwrap()
            .starts_with("T1 P1 D12.000"));
        let bad = PostArgs {
            post: "heidenhain".into(),
            ..args
        };
        let e = run(&bad).unwrap_err();
        assert!(
            e.contains("unknown post `heidenhain`") && e.contains("fanuc, linuxcnc"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A plan whose part changed, or whose verification found the program
    /// unsafe, gets no program.
    #[test]
    fn a_changed_part_or_an_unsafe_verdict_is_refused() {
        let dir = std::env::temp_dir().join(format!("thinplan-post-refuse-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plan_path = dir.join("part.plan.json");
        let out = dir.join("part.ngc");
        let args = PostArgs {
            plan: plan_path.clone(),
            post: "linuxcnc".into(),
            out: Some(out.clone()),
            tool_table: None,
            knowledge: None,
        };
        let mut changed = plan_with_one_operation();
        changed.part.sha256 = "ab".repeat(32);
        thinplan_plan::save(&changed, &plan_path).unwrap();
        let e = run(&args).unwrap_err();
        assert!(e.contains("changed since the plan was made"), "{e}");
        assert!(!out.exists());

        let mut unsafe_plan = plan_with_one_operation();
        unsafe_plan.verification = Some(Verification {
            verdict: Verdict::Unsafe,
            problems: vec![Problem {
                kind: ProblemKind::Gouge,
                operation: Some(OperationId(1)),
                line: Some(12),
                at: [0.0; 3],
                depth_mm: 1.0,
                volume_mm3: 3.0,
            }],
            left: Vec::new(),
            removed: Vec::new(),
            replanned: Vec::new(),
            planned_links: Default::default(),
            planned_order: Vec::new(),
            rounds: 1,
            cell_mm: 0.25,
            tolerance_mm: 0.05,
            provenance: Provenance::new(ProvenanceSource::Knowledge, "verification"),
        });
        thinplan_plan::save(&unsafe_plan, &plan_path).unwrap();
        let e = run(&args).unwrap_err();
        assert!(e.contains("unsafe"), "{e}");
        assert!(!out.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
