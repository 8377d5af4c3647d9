//! Prints what the reader makes of STEP files: counts, units, warnings or the error.
//!
//! ```text
//! cargo run -p thinplan-step --example step_info -- file.step [more.step …]
//! ```

fn main() {
    for arg in std::env::args().skip(1) {
        match thinplan_step::read_step_file(std::path::Path::new(&arg)) {
            Ok(m) => {
                let b = &m.brep;
                println!(
                    "{arg}: {} solids, {} shells, {} faces, {} edges, {} vertices; units {}; schema {}",
                    b.solids.len(),
                    b.shells.len(),
                    b.faces.len(),
                    b.edges.len(),
                    b.vertices.len(),
                    m.units,
                    m.schema
                );
                for w in &m.warnings {
                    println!("  warning: {w}");
                }
            }
            Err(e) => println!("error: {e}"),
        }
    }
}
