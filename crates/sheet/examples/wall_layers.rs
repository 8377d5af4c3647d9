//! Writes the figure-7.9 picture and the setup sheet for a bundled sample:
//! `cargo run -p thinplan-sheet --example wall_layers -- [SAMPLE] [SVG] [HTML]`
//! (default `tall_rib`, `docs/img/wall_layers_tall_rib.svg`, no sheet).
//! The wall drawn is the one owning most operations.

use std::collections::BTreeMap;

use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let sample = args.first().map_or("tall_rib", |s| s.as_str());
    let svg = args
        .get(1)
        .cloned()
        .unwrap_or_else(|| format!("docs/img/wall_layers_{sample}.svg"));
    let k = load_knowledge(None).map_err(|e| e.message)?;
    let setup = make_setup(&SetupRequest::default(), &k).map_err(|e| e.message)?;
    let mut s = Session::open(&format!("builtin:{sample}"), setup, k).map_err(|e| e.message)?;
    s.run_all(|_| {}).map_err(|e| e.message)?;
    let mut count: BTreeMap<_, usize> = BTreeMap::new();
    for o in &s.plan.operations {
        if let Some(f) = s.plan.machining_features.iter().find(|f| f.id == o.feature) {
            *count.entry(f.owner).or_default() += 1;
        }
    }
    let owner = count
        .iter()
        .max_by_key(|(id, n)| (**n, std::cmp::Reverse(**id)))
        .map(|(id, _)| *id)
        .ok_or("no operations")?;
    std::fs::write(&svg, thinplan_sheet::layers_svg(&s.plan, owner)).map_err(|e| e.to_string())?;
    println!("{svg}: {owner}");
    if let Some(html) = args.get(2) {
        thinplan_sheet::write_sheet(html.as_ref(), &s.plan, &s.knowledge, &s.brep, &s.warnings)?;
        println!("{html}");
    }
    Ok(())
}
