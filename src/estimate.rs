//! The cost of a run, estimated from the model before anything is assembled.
//!
//! Place in the flow: after `model`; printed by `sgbem check`, and `sgbem run` refuses a
//! scene whose estimate exceeds the memory available (so a mesh far too fine is refused in
//! milliseconds instead of allocating until the machine gives out).
//!
//! Each body assembles one dense system `G = [[A, A0], [A0ᵀ, A00]]` over its boundary
//! unknowns: `n = n_x + n_x0`, with
//!
//! * `n_x` = 2 traction unknowns per element end and prescribed-displacement component,
//!   plus 1 per free displacement component of a node, plus at most 3 rigid-mode unknowns
//!   per boundary loop;
//! * `n_x0` = 2 interface traction unknowns per interface pair node of the body, plus 1 per
//!   interface displacement component of a node.
//!
//! The bodies are assembled and condensed one after the other; a run keeps every body's
//! `G` (n²), its recovery matrix (n_x·n_x0) and its condensed `D00` (n_x0²), and condensing
//! one body needs, besides, the scaled copy of `A` and its LU factors (2·n_x²), four
//! `n_x × (n_x0+1)` work matrices and two `n_x0²` ones. In f64 (8 bytes):
//!
//! ```text
//! kept(b)  = 8 (n² + n_x n_x0 + n_x0²)
//! work(b)  = 8 (2 n_x² + 4 n_x (n_x0 + 1) + 2 n_x0²)
//! peak     = Σ_b kept(b) + max_b work(b) + mixed + contact + 64 MB
//! ```
//!
//! where `mixed` = 32 n_i² bytes for the paper's dense mixed interface operators archived
//! with `operators = true` (n_i = 4 × pairs ≤ 3000 and no junctions; none otherwise),
//! `contact` the contact stage's memory below, and 64 MB is the program itself with its
//! mesh. No dense matrix over all interfaces is counted: the engine forms none (except the
//! cross-checks' LCP and QP matrices of `both`). Time: the Galerkin pair loop costs about
//! `c_q` per element pair (`c_q` ≈ 4, 10, 30 µs for fast, standard, accurate quadrature on
//! one core of a 2020s machine), and the LU condensation `(2/3) n_x³ + 2 n_x² n_x0` flops at
//! about 1 Gflop/s; post-processing about 1 µs per (interior-field node or section point,
//! boundary element) (example 2: 525 000 such pairs in 0.3 s of CPU; a section sampled at
//! every iteration reuses its kernel integrals, so the iterations add little). All are rough:
//! they are there to tell minutes from days.
//!
//! **Contact stage** ([`ContactEstimate`], only with a unilateral interface). With `p`
//! unilateral pairs, `r` open rows (a normal row per pair, and a tangential one unless
//! `slide`), `n_u(b)` interface displacement unknowns of body b (the dense blocks of the glued
//! sparse system), `n(b)`, `n_x0(b)` as above and `k` load steps, the expected number of
//! status switches of the evolutive path is taken as `s = p` per load step (every pair
//! switches once: an upper bound on a monotone path; the paper's example 2 switches 89 of
//! its 105 pairs), and
//!
//! ```text
//! system   = C_SYSTEM · Σ_b n_u(b)³                     factorising the glued system once
//! path     = C_PATH · k s³                              evolutive: rank-one updates of the
//!                                                       open rows' Cholesky, columns on demand
//! record   = C_RECORD · (k s + 1) · Σ_b n(b) n_x0(b)    each recorded state expanded into the
//!                                                       boundary solution (history = "full")
//! checks   = k p³ · (C_ACTIVE + [both] (C_QP + C_LEMKE [r ≤ 2000]))
//! ```
//!
//! (the QP as the main solver costs `C_QP · k p³` in place of the path). The constants are
//! calibrated on `cargo bench --bench contact` (README, Speed: example 2 with 104 / 208 / 416 /
//! 832 joint elements, 105–833 pairs, 89–711 switches; one core of this shared 2-core
//! machine) and chosen to meet the two largest cases within about 30 %: system 0.24 / 1.38 s
//! at 416 / 832, path 0.56 / 7.7 s, record 2.2 / 14.0 s, active set 0.19 / 1.3 s, Lemke 0.36 /
//! 5.6 s, QP 2.5 / 16.4 s. The small cases run faster than the cubes say (overheads, caches).
//! Memory: the recorded states, `1.15 (8 Σ_b (2 nodes + 4 elements) + 82 pairs + 9 r)` bytes
//! each (k s + 1 of them with history = "full", k otherwise), the sparse glued system
//! `80 Σ_b n_u(b)²` (values and indices of the blocks, the matrix and its factor with fill),
//! the columns of the opening stiffness and the factor of A_OO, `8 r m + 4 m²` with m =
//! min(s, r) rows switched, and the dense LCP / QP matrices of the cross-checks of `both`,
//! `3 · 8 r²`. The sparse solver (over 3000 unilateral pairs) instead of the glued system and
//! the columns: `280 Σ_b n_u(b)² + 8 t` bytes, with t the entries of its system H over
//! the glued displacements and the openings, counted from the rows as the run eliminates
//! them (`contact::problem::pattern`): a joint whose sides were meshed on their own ties a
//! node to several nodes of the other side, and t then outgrows Σ n_u² (walls drawn brick
//! by brick: 6.3 t per Σ n_u², against 1.2 conforming). Measured against it (peak resident
//! memory of whole runs, `cargo bench --bench masonry`): see the README, Speed.

use crate::error::{Error, Result};
use crate::input::model::{DofClass, Model, Role};
use crate::input::scene::{Condition, Quadrature, Scene};

/// Unknown counts of one body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BodySize {
    pub n_x: usize,
    pub n_x0: usize,
    pub elements: usize,
}

/// The estimated cost of a run.
#[derive(Debug, Clone)]
pub struct Estimate {
    pub bodies: Vec<BodySize>,
    /// Peak memory in bytes.
    pub peak_bytes: f64,
    /// Assembly and condensation time in seconds.
    pub seconds: f64,
    /// Interior field and sections, in seconds.
    pub post_seconds: f64,
    /// The contact stage, with a unilateral interface.
    pub contact: Option<ContactEstimate>,
    /// The size of the files the run writes.
    pub outputs: crate::output::size::OutputSize,
}

/// The estimated cost of the contact stage (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct ContactEstimate {
    /// Unilateral pairs and open rows.
    pub pairs: usize,
    pub rows: usize,
    /// Expected status switches over the run (every pair once per load step).
    pub switches: usize,
    /// Interface displacement unknowns over all bodies (before gluing).
    pub interface_unknowns: usize,
    /// Seconds of the glued system, the main solver, the recording of its states and the
    /// cross-checks.
    pub system: f64,
    pub path: f64,
    pub record: f64,
    pub checks: f64,
    /// Bytes of the glued system, the opening stiffness's columns and factor, and the dense
    /// matrices of the cross-checks.
    pub bytes: f64,
    /// Bytes of the recorded states at most (every pair switching once per load step with
    /// history = "full"): the only part of a run that grows with its iterations, reported
    /// beside the peak and not counted for the refusal (a wall of hundreds of bricks switches
    /// about one pair in seven).
    pub history_bytes: f64,
    /// States recorded at most.
    pub states: usize,
    /// Trial steps of a collapse search before the run (0 without one).
    pub trials: usize,
}

impl ContactEstimate {
    /// Seconds of the whole contact stage.
    pub fn seconds(&self) -> f64 {
        self.system + self.path + self.record + self.checks
    }
}

/// Seconds per `n_u³` of factorising the glued system (416 / 832 joint elements: 0.24 /
/// 1.38 s for Σ n_u³ = 1.16e9 / 9.25e9).
const C_SYSTEM: f64 = 1.6e-10;
/// Seconds per `s³` of the evolutive path with `s = p` (0.56 s at p = 417, 7.7 s at p = 833:
/// 356 and 711 switches).
const C_PATH: f64 = 1.2e-8;
/// Seconds per recorded state and `Σ n·n_x0` (2.2 s for 357 states of 6.36e6, 14.0 s for 712
/// states of 2.38e7).
const C_RECORD: f64 = 9e-10;
/// Seconds per `p³` of the active set, the QP and Lemke (1.3, 16.4 and 5.6 s at p = 833; 0.19,
/// 2.5 and 0.36 s at p = 417).
const C_ACTIVE: f64 = 2.5e-9;
const C_QP: f64 = 3.0e-8;
const C_LEMKE: f64 = 9.0e-9;
/// Seconds per iteration of the sparse solver per `(Σ n_u²)^1.18` (one or two sparse
/// Cholesky factorisations of the system of displacements and openings each; running-bond
/// walls, history "final", before friction followed Coulomb's law within the iteration:
/// 0.15 s at 410 bricks, 0.29 s at 798, 0.87 s at 2 048, 1.96 s at 4 128; an iteration that
/// only moves the slip bounds now costs two triangular solves), and unilateral pairs per
/// iteration of its load step (14 iterations at 8 050 pairs, 15 at 15 974, 25 at 41 734, 32
/// at 84 896: an upper bound of one per 1 600 pairs, at least 15). The estimate of the
/// contact stage is then 1.8–2.4 times the time measured (5.1 s, 28 s and 2 min against
/// 2.8, 14 and 51 s for the 798-, 2 048- and 4 128-brick walls).
const C_SPARSE: f64 = 5.7e-9;
const SPARSE_PAIRS_PER_ITERATION: f64 = 1600.0;
/// Seconds per convex programme of the full-row solver, `C_EXACT · (Σ n_u² / EXACT_REF)^1.6`
/// (its sparse factorisations fill in faster than the operators grow): 0.64 s per programme
/// of about 10 interior point iterations on the 105-brick wall (Σ n_u² ≈ 4.2e5), 8.5 s on the
/// 410-brick wall (≈ 2.0e6; 6 programmes, 51 s), 40 ms per iteration on the 220-stone wall
/// (≈ 3e5; programmes of about 20 iterations); and the programmes of a load step with
/// friction: 1 on the 105-brick wall under wind, 6 on the 410-brick one, 10 on the 5 × 3 wall
/// near its collapse, 23 on the stone wall at 0.04 g, 100 where the fixed point stalls next to
/// a collapse (a search's trials beyond it); without friction about 3.
const C_EXACT: f64 = 0.64;
const EXACT_REF: f64 = 4.2e5;
const EXACT_PROGRAMMES_FRICTION: f64 = 30.0;
const EXACT_PROGRAMMES: f64 = 3.0;
/// Bytes per Σ n_u² of the full-row solver's LU of its statuses' system at Σ n_u² =
/// EXACT_REF, growing as (Σ n_u² / EXACT_REF)^0.24: fitted to the peak memory of running-bond
/// walls under wind (friction 0.15 at 105 bricks, 0.7 at 410 and 798), history "final", no
/// VTK, less the rest of the estimate (329 MB, 1.31 GB and 2.90 GB measured by
/// `/usr/bin/time` at 105, 410 and 798 bricks, where the estimate had 244 MB, 833 MB and
/// 1.6 GB), with 10 % to spare.
const EXACT_LU_BYTES: f64 = 222.0;
const SPARSE_MIN_ITERATIONS: f64 = 15.0;

/// The contact stage of a run of `scene` on `model` (see the module doc); None without a
/// unilateral interface.
pub fn contact(model: &Model, scene: &Scene, bodies: &[BodySize]) -> Option<ContactEstimate> {
    use crate::input::scene::{HistoryLevel, InterfaceModel, Method, Tangential};
    let (mut pairs, mut rows) = (0usize, 0usize);
    for it in &model.interfaces {
        if it.spec.model == InterfaceModel::Unilateral {
            pairs += it.pairs.len();
            rows += it.pairs.len()
                * if it.spec.tangential == Tangential::Slide {
                    1
                } else {
                    2
                };
        }
    }
    if pairs == 0 {
        return None;
    }
    let steps = scene.solve.steps().len();
    let switches = steps * pairs;
    let (p, s, k) = (pairs as f64, switches as f64 / steps as f64, steps as f64);
    let mut interface_unknowns = 0usize;
    let (mut cubes, mut squares, mut expand, mut per_state) = (0.0, 0.0, 0.0, 0.0);
    for (b, size) in model.bodies.iter().zip(bodies) {
        let n_u = b
            .dofs
            .iter()
            .flat_map(|d| d.class)
            .filter(|c| *c == DofClass::Interface)
            .count();
        interface_unknowns += n_u;
        cubes += (n_u as f64).powi(3);
        squares += (n_u as f64).powi(2);
        expand += ((size.n_x + size.n_x0) * size.n_x0) as f64;
        per_state += 8.0 * (2 * b.nodes.len() + 4 * b.elements.len()) as f64;
    }
    // Each recorded state: the boundary solution of every body, its interface results (6
    // values per pair), its history row (a status, a normal traction and an opening per
    // pair, held by the run and by the archive's thread: about 4 values), its compact record
    // (a status and an opening per row), and 15 % for the allocator and the vectors' headers
    // (measured: 1.74 MB per state on the 410-brick wall, 2.83 GB for 1196 states against
    // 0.76 GB with one; this sum gives 1.50 MB). The states' fields are shared, not copied,
    // between the VTK writer and the archive's thread.
    per_state =
        1.15 * (per_state + 8.0 * (6.0 + 4.25) * model.pair_count() as f64 + 9.0 * rows as f64);
    // The full rows record one state per load step whatever the history.
    let recorded = match scene.output.history {
        HistoryLevel::Full if scene.solve.method != Method::Exact => ((switches as f64 + 1.0)
            / scene.output.every as f64)
            .ceil()
            .max(k),
        _ => k,
    };
    // A collapse search solves one step per trial before the run itself: the two bounds and
    // the bisection down to the tolerance.
    let trials = scene
        .solve
        .collapse
        .as_ref()
        .map_or(0.0, |c| 2.0 + (c.max / c.tolerance).log2().ceil().max(0.0));
    let path = (1.0 + trials)
        * match scene.solve.method {
            Method::Qp => C_QP * k * p * p * p,
            Method::Sparse => {
                let iterations = (p / SPARSE_PAIRS_PER_ITERATION).max(SPARSE_MIN_ITERATIONS);
                // Junction cuts at whole joints: the iteration meets more free bricks, and
                // a moved cut solves the path again (28 × 28 wall: contact 5.9–6.5 s
                // against 3.2–3.5 s on the tangential cut).
                let again = if crate::contact::cuts::at_joints(scene, model) {
                    2.0
                } else {
                    1.0
                };
                again * C_SPARSE * k * iterations * squares.powf(1.18)
            }
            Method::Exact => {
                let frictional = model.interfaces.iter().any(|it| {
                    it.spec.model == InterfaceModel::Unilateral
                        && it.spec.tangential == Tangential::Friction
                });
                let programmes = if frictional {
                    EXACT_PROGRAMMES_FRICTION
                } else {
                    EXACT_PROGRAMMES
                };
                C_EXACT * k * programmes * (squares / EXACT_REF).powf(1.6)
            }
            _ => C_PATH * k * s * s * s,
        };
    let mut per_cube = match scene.solve.method {
        // The evolutive cross-check runs up to 2000 rows only.
        Method::Sparse if rows > 2000 => 0.0,
        Method::Sparse => C_PATH / 10.0,
        Method::Exact => 0.0,
        _ => C_ACTIVE,
    };
    if scene.solve.method == Method::Both {
        per_cube += C_QP + if rows <= 2000 { C_LEMKE } else { 0.0 };
    }
    let dense = match scene.solve.method {
        Method::Lcp | Method::Sparse | Method::Exact => 0.0,
        _ => 3.0 * 8.0 * (rows as f64).powi(2),
    };
    // The sparse glued system: each body's dense block (n_u² values) as entries, the matrix
    // and its Cholesky factor with fill (about 5 values per block entry, 8 bytes and an
    // index each); with the sparse solver, that and its system of displacements and
    // openings as counted from the rows (`sparse_bytes`). The columns of the opening
    // stiffness computed (one per row that switches, r values each) and the Cholesky factor
    // of A_OO over the open rows (m²/2, m ≤ the rows that switch).
    let glued = if scene.solve.method == Method::Sparse {
        sparse_bytes(model, squares)
    } else {
        5.0 * 16.0 * squares
    };
    let m = (switches as f64 / k).min(rows as f64);
    let mut opening = 8.0 * rows as f64 * m + 8.0 * m * m / 2.0;
    if scene.solve.method == Method::Exact {
        // No column of the opening stiffness: Clarabel's sparse KKT system over every dof
        // and full row and its LDL factor, about three times the glued system's; and the
        // sparse LU of the statuses' linear system (the finish), whose fill grows faster
        // than the operators.
        opening = 3.0 * glued + EXACT_LU_BYTES * squares * (squares / EXACT_REF).powf(0.24);
    }
    if scene.solve.method == Method::Sparse && rows > 2000 {
        // No column of the opening stiffness beyond the evolutive cross-check (up to 2000
        // rows).
        opening = 0.0;
    }
    Some(ContactEstimate {
        pairs,
        rows,
        switches,
        interface_unknowns,
        system: C_SYSTEM * cubes,
        path,
        record: C_RECORD * recorded * expand,
        checks: per_cube * k * p * p * p,
        bytes: dense + glued + opening,
        history_bytes: recorded * per_state,
        states: recorded as usize,
        trials: trials as usize,
    })
}

/// Bytes per Σ_b n_u² of the sparse solver besides the entries of H: the bodies'
/// Steklov–Poincaré operators and traction recoveries with the work matrices that make them
/// (the allocator keeps most of what these free), the glued system and its factor, H,
/// its copy in the elimination order with the ordering's work space, and the factor of a
/// status. Fitted with H's entries counted apart (`sparse_bytes`) on the peak resident
/// memory of running-bond walls, nj = 6, friction 0.7, self-weight and wind, history
/// "final" (b1fe7ec, 2026-12-06: conforming 20 × 20 … 64 × 64, 669 MB … 7.18 GB, and the
/// test's 14 × 14 wall drawn brick by brick, 547–557 MB): 280 keeps the estimate above the
/// measure by 7–16 % (docs/performance.md).
const SPARSE_OPERATOR_BYTES: f64 = 280.0;

/// Bytes per entry of H as emitted before its repeated positions are summed
/// ([`crate::linalg::triangle_from_entries`]: a row index and a value, 16 bytes, while H is
/// built and ordered). Fitted at half of that: the peak comes later, in the factorisations,
/// which reuse part of that memory (the drawn wall, 6.2 entries per Σ n_u², measured 14 %
/// below the estimate with 8 and would be 24 % below with 16); plus 4 for the rows of H of
/// the openings that the iterates' products read (about a third of the entries, 12 bytes
/// each; 61630dd: the peaks of the 20 × 20 … 64 × 64 walls 20–46 MB higher).
const SPARSE_ENTRY_BYTES: f64 = 12.0;

/// The memory of the sparse solver, in bytes, from the rows of `model`
/// ([`crate::contact::problem::pattern`]); `squares` = Σ_b n_u². H is assembled from its
/// entries as each body's block gives them: where the two sides of a joint were meshed on
/// their own a dof moves several glued unknowns and the entries outgrow n_u² (the wall drawn
/// brick by brick, 20 × 20: 16.3 million, against 2.4 million on the conforming wall).
fn sparse_bytes(model: &Model, squares: f64) -> f64 {
    let entries = match crate::contact::problem::pattern(model) {
        Some(p) => p.entries(),
        // The run refuses such a model (a component prescribed on one side of a joint):
        // about one entry per n_u², as on a conforming wall.
        None => squares,
    };
    SPARSE_OPERATOR_BYTES * squares + SPARSE_ENTRY_BYTES * entries
}

fn k_steps(scene: &Scene) -> f64 {
    scene.solve.steps().len() as f64
}

/// Above this many recorded unknowns (the boundary unknowns, as `sgbem check` counts them,
/// times the states of a full history, as [`contact`] counts them) a scene that does not
/// set `output.history` keeps the end of each load step ("steps"): the 105-brick wall
/// (15 555 unknowns, up to 1926 states: 3.0e7; 288 MB written with every iteration) does,
/// the other shipped scene without `history`, wall_collapse (2.8e5), does not.
pub(crate) const FULL_HISTORY_LIMIT: f64 = 1e7;

/// The default of `output.history` scaled to the scene: "steps" when neither
/// `output.history` nor `output.every` is set and a full history would record more than
/// [`FULL_HISTORY_LIMIT`] unknowns. Returns the run note that says so.
pub(crate) fn scale_history(scene: &mut Scene, model: &Model) -> Option<String> {
    use crate::input::scene::HistoryLevel;
    if scene.output.history_given || scene.output.every != 1 {
        return None;
    }
    let bodies = body_sizes(model);
    let unknowns: usize = bodies.iter().map(|b| b.n_x + b.n_x0).sum();
    let states = contact(model, scene, &bodies)?.states;
    let recorded = unknowns as f64 * states as f64;
    if recorded <= FULL_HISTORY_LIMIT {
        return None;
    }
    scene.output.history = HistoryLevel::Steps;
    Some(format!(
        "output.history = \"steps\" (the state at the end of each load step) was chosen for \
         this scene: a full history would record about {recorded:.1e} unknowns ({unknowns} \
         boundary unknowns × up to {states} states), more than {FULL_HISTORY_LIMIT:.0e}; set \
         [output] history = \"full\" (with every = N to keep every N-th iteration) to keep \
         the iterations"
    ))
}

/// The unknowns n_i of the paper's mixed interface operators of the final status where they
/// are archived: `operators = true`, up to 3000 (4 per pair) and no junctions.
pub(crate) fn mixed_unknowns(model: &Model, scene: &Scene) -> Option<f64> {
    let ni = 4.0 * model.pair_count() as f64;
    (scene.output.operators && ni > 0.0 && ni <= 3000.0 && model.junctions().is_empty())
        .then_some(ni)
}

/// Bytes the program needs besides the dense operators.
const BASE_BYTES: f64 = 64.0 * 1024.0 * 1024.0;

/// Unknown counts of every body of a model (no allocation beyond a counter per body).
pub(crate) fn body_sizes(model: &Model) -> Vec<BodySize> {
    let mut pair_nodes = vec![0usize; model.bodies.len()];
    for it in &model.interfaces {
        pair_nodes[it.body_a] += it.pairs.len();
        pair_nodes[it.body_b] += it.pairs.len();
    }
    model
        .bodies
        .iter()
        .enumerate()
        .map(|(bi, b)| {
            let mut n_x = 3 * b.loops.len();
            let mut n_x0 = 2 * pair_nodes[bi];
            for e in &b.elements {
                if let Role::Boundary(pi) = e.role {
                    let prescribed = model.parts[pi]
                        .spec
                        .components
                        .iter()
                        .filter(|c| matches!(c, Condition::Displacement(_)))
                        .count();
                    n_x += 2 * prescribed;
                }
            }
            for d in &b.dofs {
                for k in d.class {
                    match k {
                        DofClass::Known => {}
                        DofClass::Free => n_x += 1,
                        DofClass::Interface => n_x0 += 1,
                    }
                }
            }
            BodySize {
                n_x,
                n_x0,
                elements: b.elements.len(),
            }
        })
        .collect()
}

/// Estimates peak memory and time of a run of `scene` on `model` (formula above).
pub fn estimate(model: &Model, scene: &Scene) -> Estimate {
    let quadrature = scene.solve.quadrature;
    let bodies = body_sizes(model);
    let mut kept = 0.0;
    let mut work = 0.0f64;
    let mut flops = 0.0;
    let mut pairs = 0.0;
    for s in &bodies {
        let (nx, nx0) = (s.n_x as f64, s.n_x0 as f64);
        let n = nx + nx0;
        kept += 8.0 * (n * n + nx * nx0 + nx0 * nx0);
        work = work.max(8.0 * (2.0 * nx * nx + 4.0 * nx * (nx0 + 1.0) + 2.0 * nx0 * nx0));
        flops += 2.0 / 3.0 * nx * nx * nx + 2.0 * nx * nx * nx0;
        pairs += (s.elements as f64) * (s.elements as f64);
    }
    // The paper's mixed interface operators of the final status, archived (dense, several
    // copies) only for scenes of up to 3000 interface unknowns and no junctions.
    let mixed = mixed_unknowns(model, scene).map_or(0.0, |ni| 8.0 * 4.0 * ni * ni);
    let per_pair = match quadrature {
        Quadrature::Fast => 4e-6,
        Quadrature::Standard => 10e-6,
        Quadrature::Accurate => 30e-6,
    };
    // Post-processing: every interior-field node and section point meets every boundary
    // element of its body (about 1 µs each; all elements, for a section).
    let total_elements: f64 = bodies.iter().map(|b| b.elements as f64).sum();
    let mut evaluations: f64 = scene
        .output
        .sections
        .iter()
        .map(|s| s.points as f64 * total_elements)
        .sum();
    if scene.output.field {
        for (b, size) in model.bodies.iter().zip(&bodies) {
            evaluations += b.triangle_node_count() as f64 * size.elements as f64;
        }
    }
    let contact = contact(model, scene, &bodies);
    let contact_bytes = contact.as_ref().map_or(0.0, |c| c.bytes);
    // At least the final state of every step is recorded.
    let history_floor = contact.as_ref().map_or(0.0, |c| {
        c.history_bytes / c.states.max(1) as f64 * k_steps(scene)
    });
    let outputs = crate::output::size::output_size(scene, model, &bodies, contact.as_ref());
    Estimate {
        outputs,
        bodies,
        peak_bytes: kept + work + mixed + contact_bytes + history_floor + BASE_BYTES,
        seconds: pairs * per_pair + flops / 1e9,
        post_seconds: (evaluations * 1e-6).max(0.0),
        contact,
    }
}

/// The memory a run may use: `SGBEM_MEMORY_LIMIT` (bytes) if set (the user's word wins),
/// else the smallest of `MemAvailable` of /proc/meminfo, the address space left under `ulimit -v` (RLIMIT_AS) and
/// the room left under the process's cgroup memory limit (SLURM, containers: v2
/// `memory.max`, v1 `memory.limit_in_bytes`, of its cgroup and every parent), with where it
/// comes from; None when none can be read.
pub(crate) fn available_memory() -> Option<(f64, String)> {
    if let Some(b) = std::env::var("SGBEM_MEMORY_LIMIT")
        .ok()
        .and_then(|v| memory_limit(&v))
    {
        return Some((b, "SGBEM_MEMORY_LIMIT".into()));
    }
    let mut limits: Vec<(f64, String)> = Vec::new();
    limits.extend(meminfo_available().map(|b| (b, "MemAvailable in /proc/meminfo".into())));
    limits.extend(address_space_left());
    limits
        .extend(cgroup_room().map(|b| (b, "the room left under the cgroup's memory limit".into())));
    limits.into_iter().min_by(|a, b| a.0.total_cmp(&b.0))
}

/// The bytes `SGBEM_MEMORY_LIMIT` gives: a positive finite number, else None.
fn memory_limit(v: &str) -> Option<f64> {
    v.trim()
        .parse::<f64>()
        .ok()
        .filter(|b| b.is_finite() && *b > 0.0)
}

/// A note when `SGBEM_MEMORY_LIMIT` is set but is no positive number of bytes: it is
/// ignored, and the system's limits apply.
pub(crate) fn memory_limit_note() -> Option<String> {
    let v = std::env::var("SGBEM_MEMORY_LIMIT").ok()?;
    if memory_limit(&v).is_some() {
        return None;
    }
    let shown: String = v.chars().take(40).collect();
    Some(format!(
        "SGBEM_MEMORY_LIMIT = \"{shown}\" is not a positive number of bytes (e.g. 8e9): it is \
         ignored, and the memory available to the system applies"
    ))
}

/// A number of bytes in a `/proc` text: `VALUE kB` or `VALUE` (a bare number of bytes).
fn kb_or_bytes(text: &str) -> Option<f64> {
    let t = text.trim();
    match t.strip_suffix("kB") {
        Some(kb) => kb.trim().parse::<f64>().ok().map(|v| v * 1024.0),
        None => t.parse::<f64>().ok(),
    }
}

fn meminfo_available() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    text.lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))
        .and_then(kb_or_bytes)
}

/// RLIMIT_AS (the soft limit of `ulimit -v`, from /proc/self/limits) less the address
/// space the process already maps (VmSize) and what its threads will reserve, with the
/// words that say so; None when unlimited.
fn address_space_left() -> Option<(f64, String)> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let soft = limits
        .lines()
        .find_map(|l| l.strip_prefix("Max address space"))?
        .split_whitespace()
        .next()?
        .parse::<f64>()
        .ok()?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let used = status
        .lines()
        .find_map(|l| l.strip_prefix("VmSize:"))
        .and_then(kb_or_bytes)
        .unwrap_or(0.0);
    // glibc reserves up to 64 MiB of address space per malloc arena, one arena per thread
    // that allocates (the rayon workers and two more). A thread already running besides the
    // main one (`run`'s signal handler) maps its arena already (in VmSize): it takes the
    // place of one of the two, so that `check` and `run` find the same room.
    let threads = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let running = status
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .and_then(|t| t.trim().parse::<usize>().ok())
        .unwrap_or(1);
    let spare = 2usize.saturating_sub(running.saturating_sub(1));
    let arenas = 64.0 * 1024.0 * 1024.0 * (threads + spare) as f64;
    // The dense matrix products (faer's x86 kernels) reserve, in every thread that calls
    // them (the workers and the main thread), a buffer of twice the last-level cache the
    // system reports: untouched address space, but under `ulimit -v` it counts (a virtual
    // machine that reports a 260 MiB L3 reserves 545 MB per thread).
    let products = matmul_reserve_per_thread() * (threads + 1) as f64;
    let mut source = "the address space left under ulimit -v".to_string();
    if products > 0.0 {
        source.push_str(&format!(
            ", less the {} that the matrix products reserve in {} threads (twice the \
             processor's {} last-level cache each)",
            fmt_bytes(products),
            threads + 1,
            fmt_bytes(products / (2 * (threads + 1)) as f64)
        ));
    }
    // Address space is not memory in use: freed blocks, thread stacks and the libraries'
    // buffers map more than the estimate counts (measured: about 1.3 times at the peak).
    Some((((soft - used - arenas - products) / 1.5).max(0.0), source))
}

/// The address space faer's x86 matrix products reserve in each thread that calls them:
/// twice the level-3 cache of /sys/devices/system/cpu/cpu0/cache (0 where none is read,
/// or on other processors).
fn matmul_reserve_per_thread() -> f64 {
    if !cfg!(target_arch = "x86_64") {
        return 0.0;
    }
    let Ok(dirs) = std::fs::read_dir("/sys/devices/system/cpu/cpu0/cache") else {
        return 0.0;
    };
    let read = |d: &std::path::Path, f: &str| std::fs::read_to_string(d.join(f)).ok();
    let mut l3 = 0.0f64;
    for d in dirs.flatten().map(|e| e.path()) {
        let level = read(&d, "level").and_then(|t| t.trim().parse::<u32>().ok());
        let kind = read(&d, "type").unwrap_or_default();
        if level != Some(3) || !matches!(kind.trim(), "Data" | "Unified") {
            continue;
        }
        let size = read(&d, "size").and_then(|t| cache_bytes(&t));
        l3 = l3.max(size.unwrap_or(0.0));
    }
    2.0 * l3
}

/// The bytes of a sysfs cache size: `266240K`, `32M` or a bare number.
fn cache_bytes(text: &str) -> Option<f64> {
    let t = text.trim();
    let (num, unit) = match t.char_indices().last()? {
        (i, 'K') => (&t[..i], 1024.0),
        (i, 'M') => (&t[..i], 1024.0 * 1024.0),
        (i, 'G') => (&t[..i], 1024.0 * 1024.0 * 1024.0),
        _ => (t, 1.0),
    };
    num.parse::<f64>().ok().map(|v| v * unit)
}

/// The least room (limit less usage) under the memory limits of the process's cgroup and
/// its parents; None without a limit.
fn cgroup_room() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let mut dirs: Vec<(std::path::PathBuf, &str, &str)> = Vec::new();
    for line in text.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next(), parts.next()?, parts.next()?);
        let path = path.trim_start_matches('/');
        let (roots, limit, usage): (&[&str], _, _) = if controllers.is_empty() {
            (
                &["/sys/fs/cgroup", "/sys/fs/cgroup/unified"],
                "memory.max",
                "memory.current",
            )
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                &["/sys/fs/cgroup/memory"],
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        for root in roots {
            // The cgroup and each parent up to the mount's root (which may itself be the
            // process's cgroup, in a cgroup namespace).
            let mut p = std::path::Path::new(root).join(path);
            loop {
                dirs.push((p.clone(), limit, usage));
                if p == std::path::Path::new(root) || !p.pop() {
                    break;
                }
            }
        }
    }
    dirs.iter()
        .filter_map(|(d, limit, usage)| {
            let l = kb_or_bytes(&std::fs::read_to_string(d.join(limit)).ok()?)?;
            // "max", or v1's "no limit" (a page-rounded 2^63).
            if l >= 1e18 {
                return None;
            }
            let u = std::fs::read_to_string(d.join(usage))
                .ok()
                .and_then(|t| kb_or_bytes(&t))
                .unwrap_or(0.0);
            Some((l - u).max(0.0))
        })
        .min_by(|a, b| a.total_cmp(b))
}

/// "1.2 GB", "340 MB", "5.0 PB".
pub(crate) fn fmt_bytes(b: f64) -> String {
    let units = ["B", "kB", "MB", "GB", "TB", "PB", "EB"];
    let mut v = b;
    let mut i = 0;
    while v >= 1000.0 && i + 1 < units.len() {
        v /= 1000.0;
        i += 1;
    }
    if i == 0 {
        format!("{v:.0} {}", units[i])
    } else {
        format!("{v:.1} {}", units[i])
    }
}

/// "0.3 s", "4 min", "2.5 h", "12 days".
pub(crate) fn fmt_seconds(s: f64) -> String {
    if s < 60.0 {
        format!("{s:.1} s")
    } else if s < 3600.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.0} days", s / 86400.0)
    }
}

/// True while `probe` reserves memory: a failure then is an answer, not an end (the
/// program's allocator ends the process on a failed large allocation otherwise).
pub static PROBING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Reserves (and frees at once, untouched) the address space of the estimate: under a
/// limit that the figures above do not show (an `ulimit -v` set after the process started
/// its threads, an overcommit policy) the reservation fails here, with a message (I/O
/// error, exit 1), and not as a crash in the middle of the assembly.
fn probe(bytes: f64, scene_file: &std::path::Path) -> Result<()> {
    use std::sync::atomic::Ordering;
    let n = bytes.min(usize::MAX as f64 / 2.0) as usize;
    let mut v: Vec<u8> = Vec::new();
    PROBING.store(true, Ordering::SeqCst);
    let reserved = v.try_reserve_exact(n);
    drop(v);
    PROBING.store(false, Ordering::SeqCst);
    reserved.map_err(|_| {
        Error::io(
            scene_file,
            format!(
                "cannot reserve the {} of memory this run needs (the system refused the \
                 allocation: a memory limit, ulimit -v, or the overcommit policy): coarsen the \
                 mesh, or raise the limit",
                fmt_bytes(bytes)
            ),
        )
    })
}

impl Estimate {
    /// Err (input error, exit 2) when the estimate exceeds the memory available: the
    /// message names the estimate, the memory available and the fix.
    pub(crate) fn check_fits(&self, model: &Model, scene_file: &std::path::Path) -> Result<()> {
        let Some((avail, source)) = available_memory() else {
            return Ok(());
        };
        if self.peak_bytes <= avail {
            return probe(self.peak_bytes, scene_file);
        }
        let body = self
            .largest()
            .map(|(i, n)| {
                format!(
                    "; the largest system is body \"{}\" with {} boundary elements and {n} \
                     unknowns (a dense {n} × {n} matrix)",
                    model.bodies[i].name, self.bodies[i].elements
                )
            })
            .unwrap_or_default();
        Err(Error::input(
            scene_file,
            format!(
                "this run needs about {} of memory but {} are available ({source}){body}: \
                 memory grows with the square of the boundary elements per body, so coarsen \
                 the mesh (e.g. gmsh -setnumber h with a larger size, or -clscale 2 to halve \
                 the elements per edge) or split the body; `sgbem check` prints the estimate \
                 (about {} of assembly and condensation)",
                fmt_bytes(self.peak_bytes),
                fmt_bytes(avail),
                fmt_seconds(self.seconds)
            ),
        ))
    }

    /// The largest body: (index, unknowns).
    pub fn largest(&self) -> Option<(usize, usize)> {
        self.bodies
            .iter()
            .enumerate()
            .map(|(i, s)| (i, s.n_x + s.n_x0))
            .max_by_key(|(_, n)| *n)
    }

    /// One line for `sgbem check`.
    pub fn line(&self) -> String {
        let history = match &self.contact {
            Some(c) if c.states > 1 => format!(
                " (and up to {} more for a full history of up to {} states)",
                fmt_bytes(c.history_bytes),
                c.states
            ),
            _ => String::new(),
        };
        format!(
            "about {} peak memory{history}, about {} to assemble and condense, {} to \
             post-process",
            fmt_bytes(self.peak_bytes),
            fmt_seconds(self.seconds),
            fmt_seconds(self.post_seconds + 0.0)
        )
    }

    /// The contact stage's line for `sgbem check`, with a unilateral interface.
    pub(crate) fn contact_line(&self) -> Option<String> {
        self.contact.as_ref().map(|c| {
            format!(
                "up to about {} for the contact stage ({} unilateral pairs, {} rows, up to {} \
                 switches; {} interface unknowns: glued system {}, main solver {}{}, recording \
                 its states {}, cross-checks {})",
                fmt_seconds(c.seconds()),
                c.pairs,
                c.rows,
                c.switches,
                c.interface_unknowns,
                fmt_seconds(c.system),
                fmt_seconds(c.path),
                if c.trials > 0 {
                    format!(" (with the collapse search's {} trials)", c.trials)
                } else {
                    String::new()
                },
                fmt_seconds(c.record),
                fmt_seconds(c.checks)
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units() {
        assert_eq!(fmt_bytes(512.0), "512 B");
        assert_eq!(fmt_bytes(1.5e9), "1.5 GB");
        assert_eq!(fmt_bytes(1.55e14), "155.0 TB");
        assert_eq!(fmt_seconds(30.0), "30.0 s");
        assert_eq!(fmt_seconds(7200.0), "2.0 h");
    }

    #[test]
    fn sysfs_cache_sizes() {
        assert_eq!(cache_bytes("266240K\n"), Some(266240.0 * 1024.0));
        assert_eq!(cache_bytes("32M"), Some(32.0 * 1024.0 * 1024.0));
        assert_eq!(cache_bytes("4096"), Some(4096.0));
        assert_eq!(cache_bytes("K"), None);
        assert_eq!(cache_bytes(""), None);
    }
}
