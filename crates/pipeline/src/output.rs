//! Writing a planned program: a plan through a post-processor from
//! knowledge to an NC program and a tool table, written atomically. One
//! function for every driver (CLI `plan --gcode`, `post`, the GUI's export).

use std::path::Path;

use thinplan_knowledge::Knowledge;
use thinplan_plan::Plan;
use thinplan_post::NcProgram;

/// Knowledge's post-processor `id`, or an error naming the posts it has.
pub fn post_of<'k>(
    knowledge: &'k Knowledge,
    id: &str,
) -> Result<&'k thinplan_knowledge::PostProcessor, String> {
    knowledge.post(id).ok_or_else(|| {
        let known: Vec<&str> = knowledge.posts.keys().map(String::as_str).collect();
        format!(
            "unknown post `{id}` in knowledge {} (known: {})",
            knowledge.origin,
            if known.is_empty() {
                "none: the knowledge has no posts/ folder".to_string()
            } else {
                known.join(", ")
            }
        )
    })
}

/// Posts `plan` with knowledge's post `post_id` and the set-up's tool set,
/// writes the program to `out_path` (atomically) and, when asked, the
/// LinuxCNC tool table to `tool_table_path`. Nothing is written on error.
pub fn write_program(
    plan: &Plan,
    knowledge: &Knowledge,
    post_id: &str,
    out_path: &Path,
    tool_table_path: Option<&Path>,
) -> Result<NcProgram, String> {
    if let Some(v) = plan.verification.as_ref() {
        if v.verdict == thinplan_plan::Verdict::Unsafe {
            return Err(format!(
                "{}: not written: the plan's verification is unsafe ({} problem(s); `thinplan \
                 explain` and the plan's `verification` say which operations)",
                out_path.display(),
                v.problems.len()
            ));
        }
    }
    let post = post_of(knowledge, post_id)?;
    let tools = knowledge.tool_set(&plan.setup.tool_set).ok_or_else(|| {
        format!(
            "the plan's tool set `{}` is not in knowledge {}",
            plan.setup.tool_set, knowledge.origin
        )
    })?;
    let program = thinplan_post::post(plan, post, tools)
        .map_err(|e| format!("cannot post with `{post_id}`: {e}"))?;
    thinplan_plan::io::write_atomic(out_path, program.text.as_bytes())
        .map_err(|e| format!("{}: cannot write the program: {e}", out_path.display()))?;
    if let Some(t) = tool_table_path {
        thinplan_plan::io::write_atomic(t, program.tool_table.as_bytes())
            .map_err(|e| format!("{}: cannot write the tool table: {e}", t.display()))?;
    }
    Ok(program)
}
