use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::StiffnessFeatureId;
use thinplan_sheet::{layers_svg, setup_sheet, setup_sheet_with_warnings};

fn planned(name: &str) -> Session {
    let k = load_knowledge(None).unwrap();
    let setup = make_setup(&SetupRequest::default(), &k).unwrap();
    let mut s = Session::open(&format!("builtin:{name}"), setup, k).unwrap();
    s.run_all(|_| {}).unwrap();
    s
}

const VOID: [&str; 6] = ["meta", "br", "hr", "img", "link", "input"];

/// Every opened tag closed in order, attributes quoted, no stray `<` or
/// `&` in text: enough of well-formedness for a browser and an XML reader
/// of the inline SVG.
fn check_well_formed(doc: &str) -> Result<usize, String> {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = doc;
    let mut tags = 0;
    let mut in_style = false;
    while let Some(i) = rest.find('<') {
        let text = &rest[..i];
        if !in_style {
            check_text(text)?;
        }
        rest = &rest[i..];
        if let Some(r) = rest.strip_prefix("<!DOCTYPE") {
            rest = &r[r.find('>').ok_or("open doctype")? + 1..];
            continue;
        }
        let end = rest.find('>').ok_or("unclosed tag")?;
        let tag = &rest[1..end];
        rest = &rest[end + 1..];
        tags += 1;
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().ok_or(format!("</{name}> closes nothing"))?;
            if open != name {
                return Err(format!("<{open}> closed by </{name}>"));
            }
            if name == "style" {
                in_style = false;
            }
            continue;
        }
        if tag.matches('"').count() & 1 == 1 || tag.contains('<') {
            return Err(format!("bad tag <{tag}>"));
        }
        let name: String = tag
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric())
            .collect();
        if name.is_empty() {
            return Err(format!("bad tag <{tag}>"));
        }
        if tag.ends_with('/') || VOID.contains(&name.as_str()) {
            continue;
        }
        if name == "style" {
            in_style = true;
        }
        stack.push(name);
    }
    check_text(rest)?;
    if !stack.is_empty() {
        return Err(format!("unclosed: {stack:?}"));
    }
    Ok(tags)
}

fn check_text(t: &str) -> Result<(), String> {
    if t.contains('>') {
        return Err(format!("stray > in {t:?}"));
    }
    for (i, _) in t.match_indices('&') {
        let ent = &t[i..t.len().min(i + 8)];
        if !["&amp;", "&lt;", "&gt;", "&quot;", "&#39;"]
            .iter()
            .any(|e| ent.starts_with(e))
        {
            return Err(format!("bare & in {t:?}"));
        }
    }
    Ok(())
}

#[test]
fn the_checker_catches_broken_pages() {
    assert!(check_well_formed("<p><b>x</p></b>").is_err());
    assert!(check_well_formed("<p>a & b</p>").is_err());
    assert!(check_well_formed("<p>x").is_err());
    assert!(check_well_formed("<p a=\"1>x</p>").is_err());
    assert!(check_well_formed("<!DOCTYPE html><p>a &amp; b<br></p>").is_ok());
}

#[test]
fn the_sheet_is_well_formed_with_every_operation_in_order_and_the_total() {
    for name in ["tall_rib", "wing_rib"] {
        let s = planned(name);
        let html = setup_sheet_with_warnings(&s.plan, &s.knowledge, &s.brep, &s.warnings);
        let tags = check_well_formed(&html).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(tags > 100);
        assert!(!html.contains("<script"), "no scripts");
        assert!(
            !html.contains("http://") || !html.contains("src="),
            "nothing external"
        );
        assert!(
            !html.contains(" src=") && !html.contains(" href="),
            "nothing external"
        );
        // Every operation of the order, in order.
        let mut at = 0;
        for id in &s.plan.operation_order {
            let key = format!("<tr id=\"op-{id}\">");
            let i = html[at..]
                .find(&key)
                .unwrap_or_else(|| panic!("{name}: {id} missing or out of order"));
            at += i + key.len();
        }
        // The total, summed here from the operations' provenance.
        let total: f64 = s
            .plan
            .operation_order
            .iter()
            .map(|id| {
                let op = s.plan.operations.iter().find(|o| o.id == *id).unwrap();
                op.provenance.values["time_s"]
            })
            .sum();
        let key = "id=\"total-time\">";
        let i = html.find(key).expect("total") + key.len();
        let shown: f64 = html[i..i + html[i..].find('<').unwrap()].parse().unwrap();
        assert!(
            (shown - total).abs() <= 0.05 + 1e-9,
            "{name}: {shown} vs {total}"
        );
        assert!(total > 0.0);
    }
}

#[test]
fn tool_numbers_are_those_of_the_post_tool_table() {
    let s = planned("tall_rib");
    let html = setup_sheet(&s.plan, &s.knowledge, &s.brep);
    let set = s.knowledge.tool_set(&s.plan.setup.tool_set).unwrap();
    let table = thinplan_post::tool_table(set, 3);
    let mut n = 0;
    for line in table.lines() {
        let t = line.split_whitespace().next().unwrap(); // "T2"
        let id = line
            .split(';')
            .nth(1)
            .unwrap()
            .split_whitespace()
            .next()
            .unwrap();
        let key = format!("<tr id=\"tool-{t}\"><td>{t}</td><td>{id}</td>");
        assert!(html.contains(&key), "{key}");
        n += 1;
    }
    assert_eq!(n, set.tools.len());
    // Every operation row names its tool by that number.
    for op in &s.plan.operations {
        let t = set.tools.iter().position(|t| t.id == op.tool).unwrap() + 1;
        assert!(html.contains(&format!("<td>T{t} {}</td>", op.tool)));
    }
}

#[test]
fn text_is_escaped_and_bytes_are_deterministic() {
    let mut s = planned("tall_rib");
    s.plan.part.source = "builtin:<script>alert('x')</script> & \"q\"".into();
    let warnings = vec!["a <b> & c".to_string()];
    let a = setup_sheet_with_warnings(&s.plan, &s.knowledge, &s.brep, &warnings);
    let b = setup_sheet_with_warnings(&s.plan, &s.knowledge, &s.brep, &warnings);
    assert_eq!(a, b);
    check_well_formed(&a).unwrap();
    assert!(!a.contains("<script>"));
    assert!(a.contains("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; &quot;q&quot;"));
    assert!(a.contains("a &lt;b&gt; &amp; c"));
}

#[test]
fn a_plan_without_operations_or_tools_still_gives_a_page() {
    let mut s = planned("tall_rib");
    s.plan.operations.clear();
    s.plan.setup.tool_set = "missing".into();
    let html = setup_sheet(&s.plan, &s.knowledge, &s.brep);
    check_well_formed(&html).unwrap();
    assert!(html.contains("no tool set"));
}

#[test]
fn the_wall_layers_picture_shows_the_boundary_passes_of_the_rib() {
    let s = planned("tall_rib");
    let rib = s
        .plan
        .stiffness_features
        .iter()
        .find(|f| f.role == Some(thinplan_plan::WallRole::Rib))
        .unwrap()
        .id;
    let svg = layers_svg(&s.plan, rib);
    check_well_formed(&svg).unwrap();
    assert_eq!(svg, layers_svg(&s.plan, rib));
    // Every boundary z-level of the rib's operations shows as a pass.
    let mut levels: Vec<i64> = Vec::new();
    for op in &s.plan.operations {
        let f = s
            .plan
            .machining_features
            .iter()
            .find(|f| f.id == op.feature)
            .unwrap();
        if f.owner != rib {
            continue;
        }
        for m in &op.moves {
            if m.region == thinplan_plan::Region3::Boundary {
                levels.push((m.to.z * 1000.0).round() as i64);
            }
        }
    }
    levels.sort();
    levels.dedup();
    assert!(!levels.is_empty());
    for z in levels {
        let text = format!("z {} mm", thinplan_sheet::num(z as f64 / 1000.0, 3));
        assert!(svg.contains(&text), "{text}");
    }
    assert!(svg.contains("boundary pass at offset"));
    // An owner that does not exist: a picture that says so.
    let none = layers_svg(&s.plan, StiffnessFeatureId(9999));
    check_well_formed(&none).unwrap();
    assert!(none.contains("no such stiffness feature"));
}
