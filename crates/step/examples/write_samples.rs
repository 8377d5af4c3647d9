//! Writes every native sample part (`assets/parts/*.part.ron`) as STEP to
//! `DIR/NAME.step`, and `DIR/expected.json` with each part's analytic
//! volume (`{"NAME": mm³}`), for `tools/oracle/check_written.py`.
//!
//! ```text
//! cargo run -p thinplan-step --example write_samples -- DIR
//! ```

use std::collections::BTreeMap;
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(out) = std::env::args().nth(1) else {
        eprintln!("usage: write_samples DIR");
        std::process::exit(2);
    };
    let out = Path::new(&out);
    std::fs::create_dir_all(out)?;
    let parts = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/parts");
    let mut files: Vec<_> = std::fs::read_dir(&parts)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.ends_with(".part.ron"))
        })
        .collect();
    files.sort();
    let mut expected = BTreeMap::new();
    for path in files {
        let part = thinplan_native::load_part(&path)?;
        let brep = part.build()?;
        let name = part.name().to_string();
        let file = out.join(format!("{name}.step"));
        std::fs::write(&file, thinplan_step::write_step(&brep, &name))?;
        println!(
            "{}: {} faces, expected volume {}",
            file.display(),
            brep.faces.len(),
            part.expected_volume()
        );
        expected.insert(name, part.expected_volume());
    }
    let json = serde_json::to_string_pretty(&expected)?;
    std::fs::write(out.join("expected.json"), json + "\n")?;
    Ok(())
}
