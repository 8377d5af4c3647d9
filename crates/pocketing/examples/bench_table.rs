//! The table form of a `thinplan bench pockets --json` run, without running it again:
//! `cargo run --release -p thinplan-pocketing --example bench_table -- FILE.json`.
use thinplan_pocketing::bench::{format_table, BenchRow};

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: bench_table FILE.json");
        std::process::exit(2);
    };
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    match serde_json::from_str::<Vec<BenchRow>>(&text) {
        Ok(rows) => print!("{}", format_table(&rows)),
        Err(e) => {
            eprintln!("{path}: not a bench pockets JSON row list: {e}");
            std::process::exit(1);
        }
    }
}
