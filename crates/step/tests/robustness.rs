//! The reader never panics: random bytes and random mutations of fixtures.

mod common;

use proptest::prelude::*;
use thinplan_step::{read_step_bytes, Limits};

fn small() -> Limits {
    Limits {
        max_bytes: 1 << 20,
        max_entities: 10_000,
        max_depth: 32,
        max_work: 1_000_000,
    }
}

fn fixture_bytes() -> Vec<Vec<u8>> {
    [
        "box_mm.step",
        "box_inch.step",
        "assembly_nested.step",
        "plate_hole.step",
        "cone_degrees.step",
        "surface_only.step",
    ]
    .iter()
    .map(|n| std::fs::read(common::fixture(n)).unwrap())
    .collect()
}

#[derive(Debug, Clone)]
enum Mutation {
    Truncate(usize),
    Flip(usize, u8),
    Set(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
    Duplicate(usize, usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    // Bytes that matter to the grammar, so that mutations stay interesting.
    let special = prop::sample::select(b"#=();,'.$*()/\\\"0123456789EAZ_- \n".to_vec());
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Mutation::Flip(p, b)),
        (any::<usize>(), special.clone()).prop_map(|(p, b)| Mutation::Set(p, b)),
        (any::<usize>(), prop::collection::vec(special, 1..8))
            .prop_map(|(p, v)| Mutation::Insert(p, v)),
        (any::<usize>(), 1usize..64).prop_map(|(p, n)| Mutation::Delete(p, n)),
        (any::<usize>(), 1usize..200, any::<usize>())
            .prop_map(|(p, n, q)| Mutation::Duplicate(p, n, q)),
    ]
}

fn apply(data: &mut Vec<u8>, m: &Mutation) {
    let len = data.len().max(1);
    match m {
        Mutation::Truncate(p) => data.truncate(p % len),
        Mutation::Flip(p, b) => {
            if let Some(x) = data.get_mut(p % len) {
                *x ^= b;
            }
        }
        Mutation::Set(p, b) => {
            if let Some(x) = data.get_mut(p % len) {
                *x = *b;
            }
        }
        Mutation::Insert(p, v) => {
            let at = p % (data.len() + 1);
            data.splice(at..at, v.iter().copied());
        }
        Mutation::Delete(p, n) => {
            let at = p % len;
            let end = (at + n).min(data.len());
            if at < end {
                data.drain(at..end);
            }
        }
        Mutation::Duplicate(p, n, q) => {
            let at = p % len;
            let end = (at + n).min(data.len());
            if at < end {
                let piece: Vec<u8> = data[at..end].to_vec();
                let to = q % (data.len() + 1);
                data.splice(to..to, piece);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2048)) {
        let _ = read_step_bytes(&bytes, &small());
    }

    #[test]
    fn random_bytes_after_a_valid_header_never_panic(tail in prop::collection::vec(
        prop::sample::select(b"#=();,'.$*()0123456789EAZ_- \nCARTESIAN_POINTLINE".to_vec()), 0..1024)) {
        let mut bytes = b"ISO-10303-21;HEADER;ENDSEC;DATA;".to_vec();
        bytes.extend(tail);
        let _ = read_step_bytes(&bytes, &small());
    }

    #[test]
    fn mutated_fixtures_never_panic(which in 0usize..6, muts in prop::collection::vec(mutation(), 1..6)) {
        let mut data = fixture_bytes()[which].clone();
        for m in &muts {
            apply(&mut data, m);
        }
        let _ = read_step_bytes(&data, &small());
    }
}

#[test]
fn every_truncation_of_the_box_fails_cleanly() {
    let data = std::fs::read(common::fixture("box_mm.step")).unwrap();
    let end = data.windows(6).rposition(|w| w == b"ENDSEC").unwrap();
    for cut in 0..end {
        assert!(
            read_step_bytes(&data[..cut], &small()).is_err(),
            "cut at {cut}"
        );
    }
}

#[test]
fn deep_nesting_is_bounded() {
    let mut s = b"ISO-10303-21;HEADER;ENDSEC;DATA;#1=FOO(".to_vec();
    s.extend(std::iter::repeat_n(b'(', 1_000_000));
    let e = read_step_bytes(&s, &Limits::default()).unwrap_err();
    assert!(
        matches!(e.kind, thinplan_step::StepErrorKind::Limit { .. }),
        "{e}"
    );
}

#[test]
fn exponential_assembly_is_bounded_by_work() {
    // 40 levels, each mapping the level below twice: 2^40 instances.
    let mut s = String::from("ISO-10303-21;HEADER;ENDSEC;DATA;\n");
    s += "#1=( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n";
    s += "#2=( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNIT_ASSIGNED_CONTEXT((#1)) REPRESENTATION_CONTEXT('','') );\n";
    s += "#3=CARTESIAN_POINT('',(0.,0.,0.));#4=AXIS2_PLACEMENT_3D('',#3,$,$);\n";
    let box_text = std::fs::read_to_string(common::fixture("box_mm.step")).unwrap();
    // Reuse the box's entities, renumbered #5000<id>.
    let data = &box_text[box_text.find("DATA;").unwrap() + 5..box_text.rfind("ENDSEC;").unwrap()];
    let shifted = data.replace('#', "#5000");
    s += &shifted;
    let msb = box_text.find("MANIFOLD_SOLID_BREP").unwrap();
    let id = &box_text[box_text[..msb].rfind('#').unwrap() + 1..msb - 1];
    s += &format!("#100=SHAPE_REPRESENTATION('',(#5000{id}),#2);\n");
    for level in 1..40 {
        let rep = 100 + 3 * level;
        let below = rep - 3;
        s += &format!("#{}=REPRESENTATION_MAP(#4,#{below});\n", rep + 1);
        s += &format!("#{}=MAPPED_ITEM('',#{},#4);\n", rep + 2, rep + 1);
        s += &format!("#{rep}=SHAPE_REPRESENTATION('',(#{0},#{0}),#2);\n", rep + 2);
    }
    s += "ENDSEC;END-ISO-10303-21;";
    let limits = Limits {
        max_work: 2_000_000,
        ..Limits::default()
    };
    let t = std::time::Instant::now();
    let e = read_step_bytes(s.as_bytes(), &limits).unwrap_err();
    assert!(
        matches!(e.kind, thinplan_step::StepErrorKind::Limit { .. }),
        "{e}"
    );
    assert!(t.elapsed().as_secs() < 20);
}

/// Inputs kept from fuzzing (and hand-made hostile ones): each must end in
/// a result or an error, never a panic.
#[test]
fn fuzz_regression_inputs() {
    let dir = common::fixture("fuzz");
    let Ok(rd) = std::fs::read_dir(&dir) else {
        println!("note: {} is missing; skipped", dir.display());
        return;
    };
    for entry in rd.flatten() {
        let data = std::fs::read(entry.path()).unwrap();
        let _ = read_step_bytes(&data, &small());
        let _ = read_step_bytes(&data, &Limits::default());
    }
}
