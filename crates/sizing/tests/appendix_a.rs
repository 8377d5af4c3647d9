//! Appendix A of the thesis as a test: every milling test whose outcome the
//! thesis ties to the machining-feature sizes, with the model's δ_E for the
//! sizes used, on which side of the allowed deflection it falls, and what
//! Fokker reported.

use thinplan_knowledge::{Knowledge, SizingKnowledge};
use thinplan_sizing::{deflection, tall_wall_allows, MillingMode, Sizes, Wall};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reported {
    Good,
    Vibration,
    /// Not reported as good or bad on its own.
    Unclear,
}

struct Case {
    test: &'static str,
    wall: (f64, f64, f64),
    sizes: (f64, f64, f64),
    reported: Reported,
    note: &'static str,
}

use Reported::*;

/// Walls L × t × H_w and B_RF, h, H as the thesis gives them (peripheral
/// milling, finishing with a Ø12 mill). Tests that repeat the same sizes
/// with other cutting conditions are folded into one row (the note says
/// which); their differing outcomes are cutting-condition effects.
const CASES: &[Case] = &[
    Case {
        test: "TEST1/2/3-0398 (48)",
        wall: (120.0, 1.0, 48.0),
        sizes: (2.0, 12.0, 12.0),
        reported: Vibration,
        note: "re-machining on the wall top in all four runs (a_p 3, 4, 1.5)",
    },
    Case {
        test: "TEST4-0398-4A (48)",
        wall: (120.0, 1.0, 48.0),
        sizes: (11.0, 12.0, 12.0),
        reported: Good,
        note: "only B_RF changed, 2 -> 11: no re-machining, good",
    },
    Case {
        test: "TEST6/7-0398 (48)",
        wall: (120.0, 1.0, 48.0),
        sizes: (11.0, 12.0, 48.0),
        reported: Good,
        note: "satisfactory (TEST7, a_p 2: reasonable to good)",
    },
    Case {
        test: "TEST1-0398-1A (60)",
        wall: (120.0, 1.0, 60.0),
        sizes: (11.0, 12.0, 60.0),
        reported: Good,
        note: "very light vibration on top, satisfactory",
    },
    Case {
        test: "TEST2-0398-2A (60)",
        wall: (120.0, 0.8, 60.0),
        sizes: (11.0, 12.0, 60.0),
        reported: Good,
        note: "satisfactory",
    },
    Case {
        test: "TEST3-0398-3A L28",
        wall: (28.0, 0.85, 60.0),
        sizes: (11.0, 12.0, 60.0),
        reported: Vibration,
        note: "heavy vibration on top",
    },
    Case {
        test: "TEST3-0398-3A L70",
        wall: (70.0, 0.85, 60.0),
        sizes: (11.0, 12.0, 60.0),
        reported: Vibration,
        note: "light vibration on top",
    },
    Case {
        test: "TEST4-0398-4A (60)",
        wall: (120.0, 0.6, 60.0),
        sizes: (11.0, 12.0, 60.0),
        reported: Good,
        note: "satisfactory (0.05 mm structural deviation, in tolerance)",
    },
    Case {
        test: "TEST11-0398-1A",
        wall: (120.0, 0.75, 72.0),
        sizes: (11.0, 12.0, 36.0),
        reported: Vibration,
        note: "vibration marks on top, small-feature side",
    },
    Case {
        test: "TEST8-0398-1A/1B/2A",
        wall: (120.0, 1.0, 72.0),
        sizes: (11.0, 12.0, 72.0),
        reported: Vibration,
        note: "features 2-4 vibrated with every tool and a_p tried",
    },
    Case {
        test: "TEST9-0398-3A",
        wall: (120.0, 1.0, 72.0),
        sizes: (11.0, 12.0, 36.0),
        reported: Good,
        note: "satisfactory (TEST20, same sizes with a Ø20 mill: vibration)",
    },
    Case {
        test: "TEST10-0398-4A",
        wall: (120.0, 1.0, 72.0),
        sizes: (11.0, 12.0, 48.0),
        reported: Vibration,
        note: "H = 48 then 24; vibration: H = 4h too great on a 72 mm wall",
    },
    Case {
        test: "TEST17-0398-1A",
        wall: (144.0, 1.0, 72.0),
        sizes: (11.0, 12.0, 72.0),
        reported: Unclear,
        note: "\"better than TEST8-0398-2A\" (which vibrated); not called good",
    },
];

fn knowledge() -> (SizingKnowledge, f64) {
    let k = Knowledge::builtin().unwrap();
    let e = k.material("al7075").unwrap().youngs_modulus;
    (k.sizing, e)
}

fn wall(c: &Case) -> Wall {
    Wall {
        length: c.wall.0,
        thickness: c.wall.1,
        height: c.wall.2,
    }
}

fn sizes(c: &Case) -> Sizes {
    Sizes {
        b_rf: c.sizes.0,
        h: c.sizes.1,
        big_h: c.sizes.2,
    }
}

fn fmt(x: f64) -> String {
    let s = format!("{x}");
    s.strip_suffix(".0").map(str::to_string).unwrap_or(s)
}

fn reported(r: Reported) -> &'static str {
    match r {
        Good => "good",
        Vibration => "vibration",
        Unclear => "unclear",
    }
}

/// The model's verdict per case, printed as a Markdown table; returns
/// (right, wrong) among the cases with a clear outcome and, per case,
/// whether the model calls it good and whether the tall-wall rule allows it.
fn table(k: &SizingKnowledge, e: f64) -> (Vec<(f64, bool, bool)>, String) {
    let mut out = String::new();
    out.push_str("| test | wall L×t×H_w | B_RF, h, H | δ_E (mm) | model | tall-wall rule | model + rule | reported | right? | note |\n");
    out.push_str("| --- | --- | --- | ---: | --- | --- | --- | --- | --- | --- |\n");
    let mut rows = Vec::new();
    for c in CASES {
        let d = deflection(&wall(c), &sizes(c), k, e, MillingMode::Peripheral);
        let good = d <= k.allowed_deflection;
        let rule = tall_wall_allows(k, &wall(c), &sizes(c));
        let verdict = |g: bool| if g { "good" } else { "too large" };
        let right = |g: bool| match c.reported {
            Good => {
                if g {
                    "yes"
                } else {
                    "NO"
                }
            }
            Vibration => {
                if g {
                    "NO"
                } else {
                    "yes"
                }
            }
            Unclear => "–",
        };
        out.push_str(&format!(
            "| {} | {}×{}×{} | {}, {}, {} | {:.4} | {} | {} | {} | {} | {} / {} | {} |\n",
            c.test,
            fmt(c.wall.0),
            fmt(c.wall.1),
            fmt(c.wall.2),
            fmt(c.sizes.0),
            fmt(c.sizes.1),
            fmt(c.sizes.2),
            d,
            verdict(good),
            if rule { "allows" } else { "forbids" },
            verdict(good && rule),
            reported(c.reported),
            right(good),
            right(good && rule),
            c.note,
        ));
        rows.push((d, good, rule));
    }
    (rows, out)
}

fn count(rows: &[(f64, bool, bool)], with_rule: bool) -> (usize, usize) {
    let mut right = 0;
    let mut clear = 0;
    for (c, &(_, good, rule)) in CASES.iter().zip(rows) {
        let g = if with_rule { good && rule } else { good };
        match c.reported {
            Good => {
                clear += 1;
                right += usize::from(g);
            }
            Vibration => {
                clear += 1;
                right += usize::from(!g);
            }
            Unclear => {}
        }
    }
    (right, clear)
}

#[test]
fn appendix_a_table() {
    let (k, e) = knowledge();
    assert_eq!(e, 71000.0);
    let (rows, text) = table(&k, e);
    println!("{text}");
    let (right, clear) = count(&rows, false);
    let (right_rule, _) = count(&rows, true);
    println!("model alone: {right} of {clear} clear cases right");
    println!("model + tall-wall rule: {right_rule} of {clear} clear cases right");

    // The bending model alone: 10 of the 12 cases with a clear outcome.
    assert_eq!(clear, 12);
    assert_eq!(right, 10);
    // The two it misses, as DESIGN.md says: both vibrated, both under 0.01.
    let missed: Vec<&str> = CASES
        .iter()
        .zip(&rows)
        .filter(|(c, &(_, good, _))| (c.reported == Good) != good && c.reported != Unclear)
        .map(|(c, _)| c.test)
        .collect();
    assert_eq!(missed, ["TEST11-0398-1A", "TEST10-0398-4A"]);

    // TEST17 (144 long) was "better" than TEST8 (120 long, same sizes): the
    // model agrees it bends less, though still over the limit.
    let d8 = rows[9].0;
    let d17 = rows[12].0;
    assert!(d17 < d8 && d17 > k.allowed_deflection);
    // DESIGN.md's "9 of 11": the same numbers, if its 11 leave out the two
    // 48 mm rows with H = 12 (the cutting-condition tuning series) and
    // count TEST17 as not good.
    let design_11: Vec<(bool, bool)> = CASES
        .iter()
        .zip(&rows)
        .skip(2)
        .map(|(c, &(_, good, _))| (c.reported == Good, good))
        .collect();
    assert_eq!(design_11.len(), 11);
    assert_eq!(design_11.iter().filter(|(g, m)| g == m).count(), 9);

    // With the tall-wall rule: catches TEST10 (H = 4h on a 72 mm wall),
    // breaks none of the others, cannot catch TEST11 (same sizes as the
    // good TEST9, only t = 0.75 instead of 1).
    assert_eq!(right_rule, 11);
    let forbidden: Vec<&str> = CASES
        .iter()
        .zip(&rows)
        .filter(|(_, &(_, _, rule))| !rule)
        .map(|(c, _)| c.test)
        .collect();
    assert_eq!(forbidden, ["TEST10-0398-4A"]);
}

#[test]
fn the_literal_tall_wall_rule_breaks_the_60_mm_walls() {
    // Without the full-height exemption the remark "H = 4h is too great if
    // the wall height exceeds 4h" also forbids H = H_w = 5h on the 60 mm
    // walls, which were good.
    let (mut k, e) = knowledge();
    k.tall_wall.as_mut().unwrap().full_height_exempt = false;
    let (rows, text) = table(&k, e);
    println!("{text}");
    let (right, clear) = count(&rows, true);
    println!("model + literal tall-wall rule: {right} of {clear}");
    let forbidden: Vec<&str> = CASES
        .iter()
        .zip(&rows)
        .filter(|(_, &(_, _, rule))| !rule)
        .map(|(c, _)| c.test)
        .collect();
    assert_eq!(
        forbidden,
        [
            "TEST1-0398-1A (60)",
            "TEST2-0398-2A (60)",
            "TEST3-0398-3A L28",
            "TEST3-0398-3A L70",
            "TEST4-0398-4A (60)",
            "TEST8-0398-1A/1B/2A",
            "TEST10-0398-4A",
            "TEST17-0398-1A",
        ]
    );
    // Gains TEST10, loses the three good 60 mm walls.
    assert_eq!(right, 8);
}
