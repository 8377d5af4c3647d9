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
    EdgeTopology::new(mesh).loops(mesh, u, level)
}

const NONE: u32 = u32::MAX;

/// The mesh's edges (sorted vertex pairs, in lexicographic order) and each triangle's three
/// edges (edge k joins corners k and k + 1). Built once per mesh; contouring at many levels
/// then needs no hashing.
pub struct EdgeTopology {
    edges: Vec<EdgeKey>,
    tri_edges: Vec<[u32; 3]>,
}

impl EdgeTopology {
    pub fn new(mesh: &Mesh) -> Self {
        let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
        let mut edges: Vec<EdgeKey> = mesh
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| key(t[k], t[(k + 1) % 3])))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let index: HashMap<EdgeKey, u32> = edges
            .iter()
            .enumerate()
            .map(|(i, &e)| (e, i as u32))
            .collect();
        let tri_edges = mesh
            .triangles
            .iter()
            .map(|t| [0, 1, 2].map(|k| index[&key(t[k], t[(k + 1) % 3])]))
            .collect();
        EdgeTopology { edges, tri_edges }
    }

    /// Closed contour loops of `u = level` (see [`contour_loops`]).
    pub fn loops(&self, mesh: &Mesh, u: &[f64], level: f64) -> Vec<Vec<DVec2>> {
        let mut adj: Vec<[u32; 2]> = vec![[NONE, NONE]; self.edges.len()];
        let mut touched: Vec<u32> = Vec::new();
        for (t, te) in mesh.triangles.iter().zip(&self.tri_edges) {
            let above = t.map(|i| u[i as usize] > level);
            if above[0] == above[1] && above[1] == above[2] {
                continue;
            }
            let mut ends = [NONE; 2];
            let mut n = 0;
            for k in 0..3 {
                if above[k] != above[(k + 1) % 3] && n < 2 {
                    ends[n] = te[k];
                    n += 1;
                }
            }
            for (x, y) in [(ends[0], ends[1]), (ends[1], ends[0])] {
                let slot = &mut adj[x as usize];
                if slot[0] == NONE {
                    slot[0] = y;
                    touched.push(x);
                } else {
                    slot[1] = y;
                }
            }
        }
        touched.sort_unstable(); // determinism: start loops at the smallest edge key
        let point = |e: u32| {
            let (a, b) = self.edges[e as usize];
            let (ua, ub) = (u[a as usize], u[b as usize]);
            let s = (level - ua) / (ub - ua);
            mesh.vertices[a as usize].lerp(mesh.vertices[b as usize], s)
        };
        let mut visited = vec![false; self.edges.len()];
        let mut loops = Vec::new();
        for start in touched {
            if visited[start as usize] {
                continue;
            }
            let mut lp = vec![point(start)];
            visited[start as usize] = true;
            let mut prev = start;
            let mut cur = adj[start as usize][0];
            while cur != NONE {
                let c = cur;
                if c == start || visited[c as usize] {
                    break;
                }
                visited[c as usize] = true;
                lp.push(point(c));
                let nb = adj[c as usize];
                let next = if nb[0] == prev { nb[1] } else { nb[0] };
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
}
