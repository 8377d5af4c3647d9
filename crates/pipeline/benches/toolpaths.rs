//! Tool paths + post for the largest sample part:
//! `cargo bench -p thinplan-pipeline --bench toolpaths`. Prints the time of
//! stages 7 and 8 and of the post, per operation and in all.

use std::time::Instant;

use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::Stage;

fn main() {
    for name in ["wing_rib", "isogrid", "flange_cutouts"] {
        let k = load_knowledge(None).expect("knowledge");
        let setup = make_setup(&SetupRequest::default(), &k).expect("set-up");
        let mut s = Session::open(&format!("builtin:{name}"), setup, k).expect("opens");
        s.run_to(Stage::Resolve, &Default::default(), |_| {})
            .expect("stages 2-6");
        let t = Instant::now();
        s.run_stage(Stage::Operations).expect("operations");
        let t_ops = t.elapsed().as_secs_f64();
        let t = Instant::now();
        s.run_stage(Stage::Order).expect("order");
        let t_order = t.elapsed().as_secs_f64();
        let post = s.knowledge.posts.get("linuxcnc").expect("post").clone();
        let tools = s
            .knowledge
            .tool_set(&s.plan.setup.tool_set)
            .expect("tools")
            .clone();
        let t = Instant::now();
        let nc = thinplan_post::post(&s.plan, &post, &tools).expect("post");
        let t_post = t.elapsed().as_secs_f64();
        let n = s.plan.operations.len().max(1);
        let moves: usize = s.plan.operations.iter().map(|o| o.moves.len()).sum();
        println!(
            "| {name} | {} | {} | {moves} | {t_ops:.3} | {:.2} | {t_order:.4} | {t_post:.4} | {} | {:.0} |",
            s.plan.machining_features.len(),
            s.plan.operations.len(),
            1e3 * t_ops / n as f64,
            nc.line_count,
            nc.feed_length_mm,
        );
    }
}
