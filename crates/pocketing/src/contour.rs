//! Marching triangles: level sets of a P1 field on an unstructured triangle mesh.
//!
//! Written by hand: the contouring crates on crates.io (`contour`, `isoline`, `marching-squares`)
//! work on regular grids only; none traces iso-lines of a piecewise-linear field on an
//! unstructured triangulation, which is what the FEM solution is.

use glam::DVec2;
use std::collections::HashMap;

use crate::fem::Mesh;
use crate::geom::signed_area;

/// A mesh edge (sorted vertex pair) and its up to two contour neighbours.
type EdgeKey = (u32, u32);

/// Closed contour loops of `u = level`, each counter-clockwise (higher u on the left for a
/// contour around a maximum). Open chains cannot occur when u ≤ level on the boundary.
pub fn contour_loops(mesh: &Mesh, u: &[f64], level: f64) -> Vec<Vec<DVec2>> {
    // crossing point per mesh edge (key = sorted vertex pair); each triangle crossed by the
    // level contributes one segment joining two edge keys
    let mut point: HashMap<(u32, u32), DVec2> = HashMap::new();
    let mut adj: HashMap<EdgeKey, [Option<EdgeKey>; 2]> = HashMap::new();
    let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
    for t in &mesh.triangles {
        let above = t.map(|i| u[i as usize] > level);
        let n_above = above.iter().filter(|&&x| x).count();
        if n_above == 0 || n_above == 3 {
            continue;
        }
        let mut ends = Vec::with_capacity(2);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if above[k] != above[(k + 1) % 3] {
                let kk = key(a, b);
                point.entry(kk).or_insert_with(|| {
                    let (ua, ub) = (u[a as usize], u[b as usize]);
                    let s = (level - ua) / (ub - ua);
                    mesh.vertices[a as usize].lerp(mesh.vertices[b as usize], s)
                });
                ends.push(kk);
            }
        }
        debug_assert_eq!(ends.len(), 2);
        for (x, y) in [(ends[0], ends[1]), (ends[1], ends[0])] {
            let slot = adj.entry(x).or_insert([None, None]);
            if slot[0].is_none() {
                slot[0] = Some(y);
            } else {
                slot[1] = Some(y);
            }
        }
    }
    // chain
    let mut visited: HashMap<(u32, u32), bool> = adj.keys().map(|&k| (k, false)).collect();
    let mut keys: Vec<(u32, u32)> = adj.keys().copied().collect();
    keys.sort_unstable(); // determinism
    let mut loops = Vec::new();
    for start in keys {
        if visited[&start] {
            continue;
        }
        let mut lp = vec![point[&start]];
        visited.insert(start, true);
        let mut prev = start;
        let mut cur = adj[&start][0];
        while let Some(c) = cur {
            if c == start || visited[&c] {
                break;
            }
            visited.insert(c, true);
            lp.push(point[&c]);
            let nb = adj[&c];
            let next = if nb[0] == Some(prev) { nb[1] } else { nb[0] };
            prev = c;
            cur = next;
        }
        let lp = crate::geom::dedup_closed(lp);
        if lp.len() >= 3 {
            let mut lp = lp;
            if signed_area(&lp) < 0.0 {
                lp.reverse();
            }
            loops.push(lp);
        }
    }
    loops
}
