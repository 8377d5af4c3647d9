//! Topological checks of a built solid, usable on any B-rep.

use thinplan_brep::Brep;

/// Every loop a closed chain, every edge used by exactly two coedges in
/// opposite directions, and all faces connected through edges.
pub fn check_solid(b: &Brep) -> Result<(), String> {
    let mut uses = vec![(0u32, 0u32); b.edges.len()];
    for (fi, f) in b.faces.iter().enumerate() {
        if f.loops.is_empty() {
            return Err(format!("face {fi} `{}` has no loop", f.name));
        }
        for &l in &f.loops {
            let cs = &b.loops[l].coedges;
            if cs.is_empty() {
                return Err(format!("face {fi} `{}` has an empty loop", f.name));
            }
            for (i, c) in cs.iter().enumerate() {
                let n = cs[(i + 1) % cs.len()];
                if b.coedge_end(*c) != b.coedge_start(n) {
                    return Err(format!(
                        "face {fi} `{}`: loop {l} is not a closed chain",
                        f.name
                    ));
                }
                if c.forward {
                    uses[c.edge].0 += 1;
                } else {
                    uses[c.edge].1 += 1;
                }
            }
        }
    }
    for (e, u) in uses.iter().enumerate() {
        if *u != (1, 1) {
            return Err(format!(
                "edge {e} is used {} times forward and {} times backward",
                u.0, u.1
            ));
        }
    }
    // Connectivity (union-find over faces sharing edges).
    let mut parent: Vec<usize> = (0..b.faces.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut first_face = vec![usize::MAX; b.edges.len()];
    for (fi, f) in b.faces.iter().enumerate() {
        for &l in &f.loops {
            for c in &b.loops[l].coedges {
                if first_face[c.edge] == usize::MAX {
                    first_face[c.edge] = fi;
                } else {
                    let (x, y) = (find(&mut parent, first_face[c.edge]), find(&mut parent, fi));
                    parent[x] = y;
                }
            }
        }
    }
    let roots = (0..b.faces.len())
        .filter(|&i| find(&mut parent, i) == i)
        .count();
    if roots != 1 {
        return Err(format!(
            "the part falls apart into {roots} pieces (prisms that do not touch, or overlap)"
        ));
    }
    Ok(())
}
