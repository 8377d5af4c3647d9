//! `thinplan-gui [PART]`: the desktop application on a part file or
//! `builtin:NAME` (the bundled default sample when none is given).

use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let source = match args.next() {
        Some(a) if a == "-h" || a == "--help" => {
            println!("usage: thinplan-gui [PART]   (a STEP or .part.ron file, or builtin:NAME)");
            return ExitCode::SUCCESS;
        }
        Some(a) => a,
        None => thinplan_gui::default_source(),
    };
    match thinplan_gui::run(source) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("thinplan-gui: {e}");
            ExitCode::FAILURE
        }
    }
}
