//! Triangle mesh of a simply connected region (spade constrained Delaunay with refinement) and
//! linear finite elements: −Δu = 1 and the principal Dirichlet eigenfunction, u = 0 on ∂Ω.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Col, Side};
use glam::DVec2;
use spade::{ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};
use std::collections::HashSet;

use crate::PocketError;

/// A triangle mesh with boundary flags.
#[derive(Debug, Clone)]
pub struct Mesh {
    pub vertices: Vec<DVec2>,
    pub triangles: Vec<[u32; 3]>,
    pub on_boundary: Vec<bool>,
}

impl Mesh {
    /// Mesh the interior of one closed loop (counter-clockwise or not) with boundary spacing and
    /// target edge length about `h`. Only triangles inside the loop are kept.
    pub fn of_loop(boundary: &[DVec2], h: f64) -> Result<Mesh, PocketError> {
        // resample boundary with spacing <= h
        let mut pts: Vec<Point2<f64>> = Vec::new();
        let n = boundary.len();
        for i in 0..n {
            let a = boundary[i];
            let b = boundary[(i + 1) % n];
            let k = (a.distance(b) / h).ceil().max(1.0) as usize;
            for j in 0..k {
                let p = a.lerp(b, j as f64 / k as f64);
                pts.push(Point2::new(p.x, p.y));
            }
        }
        let m = pts.len();
        let edges: Vec<[usize; 2]> = (0..m).map(|i| [i, (i + 1) % m]).collect();
        let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(pts, edges)
            .map_err(|e| PocketError::Mesh(format!("{e:?}")))?;
        let max_area = 3f64.sqrt() / 4.0 * h * h;
        let area = crate::geom::signed_area(boundary).abs();
        let budget = (8.0 * area / max_area) as usize + 10 * m + 1000;
        let params = RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .with_max_allowed_area(max_area)
            .with_max_additional_vertices(budget);
        let res = cdt.refine(params);
        let excluded: HashSet<_> = res.excluded_faces.iter().copied().collect();
        let mut map = vec![u32::MAX; cdt.num_vertices()];
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for f in cdt.inner_faces() {
            if excluded.contains(&f.fix()) {
                continue;
            }
            let vs = f.vertices();
            let mut tri = [0u32; 3];
            for (k, v) in vs.iter().enumerate() {
                let idx = v.fix().index();
                if map[idx] == u32::MAX {
                    map[idx] = vertices.len() as u32;
                    let p = v.position();
                    vertices.push(DVec2::new(p.x, p.y));
                }
                tri[k] = map[idx];
            }
            // ensure counter-clockwise
            let (a, b, c) = (
                vertices[tri[0] as usize],
                vertices[tri[1] as usize],
                vertices[tri[2] as usize],
            );
            if (b - a).perp_dot(c - a) < 0.0 {
                tri.swap(1, 2);
            }
            triangles.push(tri);
        }
        let mut on_boundary = vec![false; vertices.len()];
        for e in cdt.undirected_edges() {
            if cdt.is_constraint_edge(e.fix()) {
                for v in e.vertices() {
                    let idx = map[v.fix().index()];
                    if idx != u32::MAX {
                        on_boundary[idx as usize] = true;
                    }
                }
            }
        }
        if triangles.is_empty() {
            return Err(PocketError::Mesh("empty mesh".into()));
        }
        Ok(Mesh {
            vertices,
            triangles,
            on_boundary,
        })
    }

    /// Longest edge length in the mesh.
    pub fn max_edge(&self) -> f64 {
        let mut m: f64 = 0.0;
        for t in &self.triangles {
            for k in 0..3 {
                let a = self.vertices[t[k] as usize];
                let b = self.vertices[t[(k + 1) % 3] as usize];
                m = m.max(a.distance(b));
            }
        }
        m
    }
}

/// Which scalar field generates the contours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Field {
    /// −Δu = 1, u = 0 on ∂Ω (one sparse Cholesky solve).
    #[default]
    Poisson,
    /// Principal Dirichlet eigenfunction −Δu = λu by inverse iteration.
    Eigen,
}

/// The solved field.
#[derive(Debug, Clone)]
pub struct Solution {
    /// Nodal values, normalised to max 1.
    pub u: Vec<f64>,
    /// Nodal values before normalisation.
    pub raw: Vec<f64>,
    /// Principal eigenvalue estimate (Rayleigh quotient) when `Field::Eigen` was solved.
    pub eigenvalue: Option<f64>,
}

/// Assembled P1 stiffness and (consistent) mass matrices restricted to interior vertices.
struct System {
    k: SparseColMat<usize, f64>,
    m: SparseColMat<usize, f64>,
    load: Vec<f64>,
    dof: Vec<usize>, // mesh vertex -> dof index or usize::MAX
    ndof: usize,
}

fn assemble(mesh: &Mesh) -> Result<System, PocketError> {
    let mut dof = vec![usize::MAX; mesh.vertices.len()];
    let mut ndof = 0;
    for (i, &b) in mesh.on_boundary.iter().enumerate() {
        if !b {
            dof[i] = ndof;
            ndof += 1;
        }
    }
    if ndof == 0 {
        return Err(PocketError::Mesh("mesh has no interior vertex".into()));
    }
    let mut kt = Vec::with_capacity(mesh.triangles.len() * 9);
    let mut mt = Vec::with_capacity(mesh.triangles.len() * 9);
    let mut load = vec![0.0; ndof];
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.vertices[i as usize]);
        let area2 = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        let area = 0.5 * area2.abs();
        if area <= 0.0 {
            continue;
        }
        // gradients of barycentric functions: grad φ_i = perp(edge opposite) / (2A)
        let e = [p[2] - p[1], p[0] - p[2], p[1] - p[0]];
        for a in 0..3 {
            let da = dof[t[a] as usize];
            if da == usize::MAX {
                continue;
            }
            load[da] += area / 3.0;
            for b in 0..3 {
                let db = dof[t[b] as usize];
                if db == usize::MAX {
                    continue;
                }
                let kab = e[a].dot(e[b]) / (4.0 * area);
                let mab = if a == b { area / 6.0 } else { area / 12.0 };
                kt.push(Triplet::new(da, db, kab));
                mt.push(Triplet::new(da, db, mab));
            }
        }
    }
    let k = SparseColMat::try_new_from_triplets(ndof, ndof, &kt)
        .map_err(|e| PocketError::Solver(format!("{e:?}")))?;
    let m = SparseColMat::try_new_from_triplets(ndof, ndof, &mt)
        .map_err(|e| PocketError::Solver(format!("{e:?}")))?;
    Ok(System {
        k,
        m,
        load,
        dof,
        ndof,
    })
}

/// Solve the chosen field on the mesh; u = 0 on boundary vertices; normalised so max u = 1.
pub fn solve(mesh: &Mesh, field: Field) -> Result<Solution, PocketError> {
    let sys = assemble(mesh)?;
    let llt = sys
        .k
        .sp_cholesky(Side::Lower)
        .map_err(|e| PocketError::Solver(format!("{e:?}")))?;
    let mut x = Col::<f64>::from_fn(sys.ndof, |i| sys.load[i]);
    llt.solve_in_place(x.as_mut());
    let mut eigenvalue = None;
    if field == Field::Eigen {
        // inverse iteration K x_{k+1} = M x_k starting from the Poisson solution (already a
        // very good approximation of the principal mode)
        let mut lam_prev = f64::INFINITY;
        for _ in 0..200 {
            let mx = &sys.m * &x;
            let mut y = mx.clone();
            llt.solve_in_place(y.as_mut());
            let ky_dot_y = {
                let ky = &sys.k * &y;
                (0..sys.ndof).map(|i| ky[i] * y[i]).sum::<f64>()
            };
            let my_dot_y = {
                let my = &sys.m * &y;
                (0..sys.ndof).map(|i| my[i] * y[i]).sum::<f64>()
            };
            let lam = ky_dot_y / my_dot_y;
            let norm = my_dot_y.sqrt();
            x = Col::from_fn(sys.ndof, |i| y[i] / norm);
            let done = ((lam - lam_prev) / lam).abs() < 1e-12;
            lam_prev = lam;
            eigenvalue = Some(lam);
            if done {
                break;
            }
        }
    }
    let mut raw = vec![0.0; mesh.vertices.len()];
    for (v, &d) in sys.dof.iter().enumerate() {
        if d != usize::MAX {
            raw[v] = x[d];
        }
    }
    // principal eigenvector may come out negative
    let sum: f64 = raw.iter().sum();
    if sum < 0.0 {
        raw.iter_mut().for_each(|v| *v = -*v);
    }
    let max = raw.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max <= 0.0 {
        return Err(PocketError::Solver("non-positive solution".into()));
    }
    let u = raw.iter().map(|v| v / max).collect();
    Ok(Solution { u, raw, eigenvalue })
}
