//! Test-local assembly of the Galerkin operators on one closed loop (continuous P1
//! displacement hats, discontinuous P1 tractions), for the operator-level checks of
//! docs/formulation.md §7 items 5–8. Not the crate's assembly: deliberately plain and dense.
#![allow(dead_code, clippy::needless_range_loop)]

use faer::Mat;
use rayon::prelude::*;
use sgbem::bem::galerkin::{element_mass, pair_blocks, ElementRef, PairBlocks, Segment};
use sgbem::bem::kernels::{Material, Vec2};
use sgbem::bem::quadrature::QuadratureSettings;

/// One closed loop: element e runs from node e to node e+1 (mod n).
pub struct Loop {
    pub nodes: Vec<Vec2>,
    pub elems: Vec<ElementRef>,
}

impl Loop {
    pub fn from_nodes(nodes: Vec<Vec2>) -> Self {
        let n = nodes.len();
        let elems = (0..n)
            .map(|e| ElementRef::new(Segment::new(nodes[e], nodes[(e + 1) % n]), [e, (e + 1) % n]))
            .collect();
        Loop { nodes, elems }
    }

    /// Polygon with `per_side` equal elements on each side (vertices counter-clockwise).
    pub fn polygon(vertices: &[Vec2], per_side: usize) -> Self {
        let mut nodes = Vec::new();
        for (i, p) in vertices.iter().enumerate() {
            let q = vertices[(i + 1) % vertices.len()];
            for j in 0..per_side {
                let t = j as f64 / per_side as f64;
                nodes.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        Self::from_nodes(nodes)
    }

    /// Inscribed regular polygon of a circle, counter-clockwise.
    pub fn circle(center: Vec2, radius: f64, n: usize) -> Self {
        let nodes = (0..n)
            .map(|j| {
                let a = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
                [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
            })
            .collect();
        Self::from_nodes(nodes)
    }

    pub fn segments(&self) -> Vec<Segment> {
        self.elems.iter().map(|e| e.seg).collect()
    }

    pub fn n_elems(&self) -> usize {
        self.elems.len()
    }

    /// Node of end `a` of element `e`.
    pub fn node(&self, e: usize, a: usize) -> usize {
        self.elems[e].nodes[a]
    }
}

/// The A1 quadrilateral of docs/formulation.md Appendix A.
pub const QUAD: [Vec2; 4] = [[0.0, 0.0], [1.0, 0.0], [1.2, 0.6], [0.1, 0.8]];

/// Dense operators. Traction DOF (e, a, i) = 4e + 2a + i; displacement DOF (node j, i) = 2j + i.
pub struct Operators {
    /// Traction × traction single layer (discontinuous P1 both sides).
    pub v: Mat<f64>,
    /// Traction test × displacement trial double layer.
    pub k: Mat<f64>,
    /// Hat × hat regularised hypersingular.
    pub d: Mat<f64>,
    /// Traction test × hat trial mass.
    pub m: Mat<f64>,
    /// Hat × hat single layer (continuous traction hats), for the degenerate-scale check.
    pub v_hat: Mat<f64>,
}

pub fn all_pairs(lp: &Loop, mat: &Material, s: &QuadratureSettings) -> Vec<Vec<PairBlocks>> {
    (0..lp.n_elems())
        .into_par_iter()
        .map(|e| {
            (0..lp.n_elems())
                .map(|f| pair_blocks(mat, &lp.elems[e], &lp.elems[f], s))
                .collect()
        })
        .collect()
}

pub fn assemble(lp: &Loop, mat: &Material, s: &QuadratureSettings) -> Operators {
    let ne = lp.n_elems();
    let nn = lp.nodes.len();
    let pairs = all_pairs(lp, mat, s);
    let mut v = Mat::<f64>::zeros(4 * ne, 4 * ne);
    let mut k = Mat::<f64>::zeros(4 * ne, 2 * nn);
    let mut d = Mat::<f64>::zeros(2 * nn, 2 * nn);
    let mut m = Mat::<f64>::zeros(4 * ne, 2 * nn);
    let mut v_hat = Mat::<f64>::zeros(2 * nn, 2 * nn);
    for e in 0..ne {
        let me = element_mass(&lp.elems[e].seg);
        for a in 0..2 {
            let ja = lp.node(e, a);
            for b in 0..2 {
                let jb = lp.node(e, b);
                for i in 0..2 {
                    m[(4 * e + 2 * a + i, 2 * jb + i)] += me[a][b];
                }
            }
            for f in 0..ne {
                let pb = &pairs[e][f];
                for b in 0..2 {
                    let jb = lp.node(f, b);
                    for i in 0..2 {
                        for kk in 0..2 {
                            v[(4 * e + 2 * a + i, 4 * f + 2 * b + kk)] += pb.v[a][b][i][kk];
                            k[(4 * e + 2 * a + i, 2 * jb + kk)] += pb.k[a][b][i][kk];
                            d[(2 * ja + i, 2 * jb + kk)] += pb.d[a][b][i][kk];
                            v_hat[(2 * ja + i, 2 * jb + kk)] += pb.v[a][b][i][kk];
                        }
                    }
                }
            }
        }
    }
    Operators { v, k, d, m, v_hat }
}

pub fn matvec(a: &Mat<f64>, x: &[f64]) -> Vec<f64> {
    assert_eq!(a.ncols(), x.len());
    (0..a.nrows())
        .map(|i| (0..a.ncols()).map(|j| a[(i, j)] * x[j]).sum())
        .collect()
}

pub fn matvec_t(a: &Mat<f64>, x: &[f64]) -> Vec<f64> {
    assert_eq!(a.nrows(), x.len());
    (0..a.ncols())
        .map(|j| (0..a.nrows()).map(|i| a[(i, j)] * x[i]).sum())
        .collect()
}

pub fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

pub fn mat_max_abs(a: &Mat<f64>) -> f64 {
    let mut m: f64 = 0.0;
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            m = m.max(a[(i, j)].abs());
        }
    }
    m
}

/// max |A − Aᵀ| / max |A|.
pub fn asymmetry(a: &Mat<f64>) -> f64 {
    let mut m: f64 = 0.0;
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            m = m.max((a[(i, j)] - a[(j, i)]).abs());
        }
    }
    m / mat_max_abs(a)
}

/// Nodal displacement vector of a field.
pub fn nodal_displacement(lp: &Loop, u: impl Fn(Vec2) -> Vec2) -> Vec<f64> {
    lp.nodes.iter().flat_map(|&x| u(x)).collect()
}

/// Discontinuous traction values σ(x) n_e at both ends of every element.
pub fn element_tractions(lp: &Loop, sigma: impl Fn(Vec2) -> [[f64; 2]; 2]) -> Vec<f64> {
    let mut t = Vec::with_capacity(4 * lp.n_elems());
    for el in &lp.elems {
        let n = el.seg.normal();
        for x in [el.seg.p, el.seg.q] {
            let s = sigma(x);
            t.push(s[0][0] * n[0] + s[0][1] * n[1]);
            t.push(s[1][0] * n[0] + s[1][1] * n[1]);
        }
    }
    t
}

/// `sqrt(Σ r² / w)` with w the lumped mass of each traction test function (L_e/2): an
/// approximation of the L² norm of the residual function behind a Galerkin residual vector.
pub fn traction_row_norm(lp: &Loop, r: &[f64]) -> f64 {
    let mut s = 0.0;
    for (e, el) in lp.elems.iter().enumerate() {
        let w = 0.5 * el.seg.length();
        for c in 0..4 {
            s += r[4 * e + c] * r[4 * e + c] / w;
        }
    }
    s.sqrt()
}

/// Same for hat rows: lumped mass (L_prev + L_next)/2.
pub fn hat_row_norm(lp: &Loop, r: &[f64]) -> f64 {
    let mut w = vec![0.0; lp.nodes.len()];
    for el in &lp.elems {
        let h = 0.5 * el.seg.length();
        w[el.nodes[0]] += h;
        w[el.nodes[1]] += h;
    }
    let mut s = 0.0;
    for (j, wj) in w.iter().enumerate() {
        s += (r[2 * j] * r[2 * j] + r[2 * j + 1] * r[2 * j + 1]) / wj;
    }
    s.sqrt()
}

/// Calderón residuals `r1 = V t − (½M + K) u` and `r2 = D u − (½Mᵀ − Kᵀ) t`
/// (docs/formulation.md §2.3), optionally with body-force terms added by the caller.
pub fn calderon_residuals(ops: &Operators, u: &[f64], t: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let vt = matvec(&ops.v, t);
    let mu = matvec(&ops.m, u);
    let ku = matvec(&ops.k, u);
    let r1 = (0..vt.len()).map(|i| vt[i] - 0.5 * mu[i] - ku[i]).collect();
    let du = matvec(&ops.d, u);
    let mt = matvec_t(&ops.m, t);
    let kt = matvec_t(&ops.k, t);
    let r2 = (0..du.len()).map(|i| du[i] - 0.5 * mt[i] + kt[i]).collect();
    (r1, r2)
}

/// Least-squares slope of log(err) against log(h).
pub fn loglog_slope(h: &[f64], err: &[f64]) -> f64 {
    let n = h.len() as f64;
    let xs: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let ys: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// Symmetric eigenvalues (ascending) of a dense symmetric matrix.
pub fn sym_eigenvalues(a: &Mat<f64>) -> Vec<f64> {
    a.self_adjoint_eigenvalues(faer::Side::Lower)
        .expect("symmetric eigenvalue solver failed")
}

/// Smooth test fields for weak residual norms.
pub fn smooth_test_fields() -> [fn(Vec2) -> Vec2; 3] {
    [
        |x| [(2.0 * x[0] + x[1]).cos(), (x[0] - 3.0 * x[1]).sin()],
        |x| [x[0] * x[1] + 0.3, (1.5 * x[1]).exp() - x[0]],
        |x| [(3.0 * x[0]).sin() * x[1], (2.0 * x[0] * x[1]).cos()],
    ]
}

/// Weak residuals `max_v |Σ v(x_a)·r_a|` over [`smooth_test_fields`]: the residual functions
/// tested against the interpolants of fixed smooth fields (traction rows at the element
/// ends, hat rows at the nodes).
pub fn weak_residuals(lp: &Loop, r1: &[f64], r2: &[f64]) -> (f64, f64) {
    let (mut w1, mut w2): (f64, f64) = (0.0, 0.0);
    for v in smooth_test_fields() {
        let mut s1 = 0.0;
        for (e, el) in lp.elems.iter().enumerate() {
            for (a, x) in [el.seg.p, el.seg.q].into_iter().enumerate() {
                let vx = v(x);
                s1 += vx[0] * r1[4 * e + 2 * a] + vx[1] * r1[4 * e + 2 * a + 1];
            }
        }
        let mut s2 = 0.0;
        for (j, &x) in lp.nodes.iter().enumerate() {
            let vx = v(x);
            s2 += vx[0] * r2[2 * j] + vx[1] * r2[2 * j + 1];
        }
        w1 = w1.max(s1.abs());
        w2 = w2.max(s2.abs());
    }
    (w1, w2)
}
