//! Result records: what a solve produces, in plain data that post-processing and the
//! writers read. Nothing here computes.
//!
//! The contact stage's figures for `summary.json`'s `contact` and `qp.info` blocks are here
//! too ([`ContactSummary`] and what it holds), as `#[derive(Serialize)]` records that
//! `output::summary::Summary` writes; as every record of the summary, they declare their
//! fields in alphabetical order (the order the file has always had; the test
//! `output::summary::tests::keys_are_sorted` holds them to it).

use std::collections::BTreeMap;

use serde::Serialize;

/// The boundary solution of one body, in global components.
#[derive(Debug, Clone, Default)]
pub struct BodyField {
    /// Displacement of each boundary node (body-local numbering, as `Body::nodes`).
    pub u: Vec<[f64; 2]>,
    /// Traction `t = σ n` at the two ends of each element (as `Body::elements`).
    pub t: Vec<[[f64; 2]; 2]>,
    /// The Galerkin-weighted reaction `∫ψ_n t` of each node held by a displacement condition,
    /// along its known directions (global x, y; zero elsewhere): the nodal force that the
    /// discrete problem balances exactly. Empty where unknown (read from an archive).
    pub reaction: Vec<[f64; 2]>,
}

/// State of one interface pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairStatus {
    /// In contact (real): tractions transmitted, displacements shared.
    Closed,
    /// Detached (virtual): no traction, displacements independent.
    Open,
}

/// Result at one interface pair, in the pair frame (s, n) of the first body.
#[derive(Debug, Clone, Copy)]
pub struct PairResult {
    pub status: PairStatus,
    /// Traction on the first body: tangential, normal (tension positive).
    pub traction: [f64; 2],
    /// Relative displacement `u_B − u_A`: tangential (slip), normal (opening).
    pub jump: [f64; 2],
    /// Friction pairs: whether the closed pair slips (`Some(true)`) or sticks; `None` for
    /// other pairs.
    pub slipping: Option<bool>,
    /// Friction pairs: the accumulated slip path Σ|Δs| over the load steps while closed.
    pub slip: f64,
}

impl PairResult {
    /// `stick`, `slip` or `open` for friction pairs; `None` for other pairs.
    pub fn tangential_status(&self) -> Option<&'static str> {
        match (self.status, self.slipping) {
            (_, None) => None,
            (PairStatus::Open, _) => Some("open"),
            (PairStatus::Closed, Some(true)) => Some("slip"),
            (PairStatus::Closed, Some(false)) => Some("stick"),
        }
    }
}

/// Results of one interface.
#[derive(Debug, Clone, Default)]
pub struct InterfaceResult {
    pub pairs: Vec<PairResult>,
}

/// One row of the contact history: the state after one iteration of one load step.
#[derive(Debug, Clone)]
pub struct HistoryRow {
    pub load_step: usize,
    pub load_factor: f64,
    /// Iteration within the load step (0: the initial status).
    pub iteration: usize,
    /// Which solver produced the row: "lcp" (evolutive), "active-set", "lemke", "qp".
    pub solver: &'static str,
    /// Per interface, per pair: status, normal traction (tension positive) and normal
    /// opening (current normal distance, 0 where closed).
    pub status: Vec<Vec<PairStatus>>,
    pub normal_traction: Vec<Vec<f64>>,
    pub normal_opening: Vec<Vec<f64>>,
    /// Per interface: detached length (elements whose two ends are open).
    pub detached_length: Vec<f64>,
}

/// The contact history of a run.
#[derive(Debug, Clone, Default)]
pub struct History {
    pub rows: Vec<HistoryRow>,
}

/// How a run ended, as `summary.json`'s and the archive's `status`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunStatus {
    /// One linear solve (no unilateral interface).
    Solved,
    /// The contact problem converged at every load step.
    Converged,
    /// The contact problem did not converge (the failure says why).
    NotConverged,
    /// A result holds numbers that are not finite.
    NonFinite,
}

impl RunStatus {
    /// The status as written in the outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            RunStatus::Solved => "solved",
            RunStatus::Converged => "converged",
            RunStatus::NotConverged => "not converged",
            RunStatus::NonFinite => "failed: non-finite results",
        }
    }
}

impl serde::Serialize for RunStatus {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// `summary.json`'s `contact` block: the contact stage's own figures.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum ContactSummary {
    /// Without unilateral interfaces: one linear solve.
    Linear(LinearSummary),
    /// The contact problem solved along the load path.
    Contact(Box<ContactSolveSummary>),
}

/// The `contact` block of a run without unilateral interfaces.
#[derive(Debug, Clone, Serialize)]
pub struct LinearSummary {
    /// Where three or more bodies meet at a point (without `implied_slipping`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub junctions: Option<Junctions>,
    /// "linear (no unilateral interface)".
    pub solver: &'static str,
}

/// The `contact` block of a contact run: the main solver's figures summed over the load
/// steps and the cross-checks of every step.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSolveSummary {
    /// With `[solve] collapse`: the search for the largest multiplier with an equilibrium.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collapse: Option<CollapseSummary>,
    /// The largest relative complementarity violation left at a load step.
    pub complementarity_residual: f64,
    /// Whether every load step converged.
    pub converged: bool,
    /// Each cross-check solver at each load step, in the order they ran.
    pub cross_checks: Vec<CrossCheck>,
    /// The glued unknowns (the size of the sparse base system).
    pub interface_system_size: usize,
    /// Status switches of the main solver, summed over the load steps.
    pub iterations: usize,
    /// Where three or more bodies meet at a point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub junctions: Option<Junctions>,
    pub load_steps: usize,
    /// The columns of the opening stiffness computed.
    pub opening_stiffness_columns: usize,
    /// What the contact problem is, in words.
    pub problem: &'static str,
    /// The main solver's name (`lcp`, `sparse`, `qp`, ...).
    pub solver: &'static str,
}

/// One cross-check of one load step: another solver from the same state, its statuses
/// compared with the main solver's pair by pair.
#[derive(Debug, Clone, Serialize)]
pub struct CrossCheck {
    pub converged: bool,
    /// Pairs whose statuses differ but both solve the step: closed without normal force in
    /// one result, open without opening in the other.
    pub degenerate_pairs: usize,
    /// Pairs whose status differs from the main solver's, the degenerate ones left out.
    pub differing_pairs: usize,
    /// Why the solver failed (`null` where it did not).
    pub failure: Option<String>,
    pub info: SolverInfo,
    pub iterations: usize,
    /// The load step (from 0).
    pub load_step: usize,
    pub outer_iterations: usize,
    pub solver: &'static str,
}

/// A solver's own figures at a load step (`info`): Lemke's pivots, the QP's iterations and
/// problem size, and, for any solver, the QP's rescues of the pivoting path and the changes
/// of the friction fixed point's slip bounds; a figure is left out where it does not apply.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SolverInfo {
    /// QP: the constraints of the last QP solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraints: Option<usize>,
    /// Lemke and QP: pivots that finished the friction rows of their statuses.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_finishing_pivots: Option<usize>,
    /// With friction: the change of the slip bounds at each outer iteration.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_outer_changes: Option<Vec<f64>>,
    /// QP: the interior point's iterations of the last QP solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u32>,
    /// QP: the objective of the last QP solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub objective: Option<f64>,
    /// Lemke: the pivots of the last inner problem solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pivots: Option<usize>,
    /// Inner solves whose pivoting path the QP completed (where there was one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub qp_rescues: Option<usize>,
    /// QP: the interior point solver's status.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solver_status: Option<String>,
    /// Lemke and QP: dense solves repeated because stick rows of pairs that closed had to
    /// be tied (a stick row ties as its pair closes); left out where none was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stick_tie_resolves: Option<usize>,
    /// QP: the variables of the last QP solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variables: Option<usize>,
}

/// The `contact.junctions` block: the points where three or more bodies meet and the pair
/// components there that the kept rows imply (no row of their own).
#[derive(Debug, Clone, Serialize)]
pub struct Junctions {
    /// The implied components by interface.
    pub implied: BTreeMap<String, Vec<ImpliedComponent>>,
    pub implied_components: usize,
    /// Contact runs: the implied tangential components that slip in the final state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub implied_slipping: Option<ImpliedSlipping>,
    pub most_bodies_at_a_point: usize,
    pub points: usize,
    /// Which rows are kept, in words.
    pub rule: &'static str,
}

/// One implied pair component: `normal` or `tangential`, at the pair's point.
#[derive(Debug, Clone, Serialize)]
pub struct ImpliedComponent {
    pub component: &'static str,
    pub x: [f64; 2],
}

/// The `contact.junctions.implied_slipping` block: closed pairs with friction whose implied
/// tangential component slips.
#[derive(Debug, Clone, Serialize)]
pub struct ImpliedSlipping {
    pub at: Vec<SlippingPair>,
    pub count: usize,
    pub largest_slip: f64,
    /// What the figures mean, in words.
    pub meaning: &'static str,
}

/// One pair of [`ImpliedSlipping`]: its interface, point and tangential jump.
#[derive(Debug, Clone, Serialize)]
pub struct SlippingPair {
    pub interface: String,
    pub slip: f64,
    pub x: [f64; 2],
}

/// The `contact.collapse` block: the bisection for the largest load multiplier with an
/// equilibrium.
#[derive(Debug, Clone, Serialize)]
pub struct CollapseSummary {
    /// The smallest multiplier found without an equilibrium (`null` where `max` stands).
    pub collapses_at: Option<f64>,
    pub max: f64,
    /// Why the smallest multiplier without an equilibrium has none (`null` if none).
    pub mechanism: Option<String>,
    /// The motion of that mechanism, body by body (left out where `max` stands); where the
    /// rigid-block statics leaves that trial undecided, the motion the solver found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<Vec<MechanismBody>>,
    /// The largest multiplier with an equilibrium: the run's.
    pub multiplier: f64,
    /// Which state the results are, in words.
    pub state: &'static str,
    pub tolerance: f64,
    /// Every trial in the order made.
    pub trials: Vec<CollapseTrial>,
    /// The largest t at which interface forces within the pairs' laws balance every body
    /// that no displacement condition holds (the rigid-block statics, Coulomb's cone taken
    /// as it is: an upper bound of the multiplier); `null` where there is none.
    pub upper_bound: Option<f64>,
    /// What `upper_bound` is, or why there is none.
    pub upper_bound_meaning: String,
}

/// One trial of the collapse search: the multiplier and whether an equilibrium exists.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct CollapseTrial {
    pub stands: bool,
    pub t: f64,
    /// Neither an equilibrium nor its absence is shown: a "no equilibrium" that the
    /// rigid-block statics cannot confirm, a friction fixed point that did not settle, a
    /// convex programme without progress. Counted as not standing, so the multiplier is a
    /// lower bound there; left out where false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub undecided: bool,
    /// Not solved: more than 10 % above the rigid-block statics' bound, where no equilibrium
    /// exists by proof; left out where false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub by_statics: bool,
    /// The equal steps of t from the unloaded state the trial was solved in: 1, or 2
    /// where one step left it undecided; left out where 1 (and 0, not solved, with
    /// `by_statics`).
    #[serde(skip_serializing_if = "one_or_none")]
    pub steps: usize,
}

fn one_or_none(steps: &usize) -> bool {
    *steps <= 1
}

/// The rigid motion of one body in a mechanism: the velocity `translation` of the point
/// `centroid` (the centroid of the body's nodes) and the angular velocity `rotation`
/// (anticlockwise positive), so that a point x moves at `t + ω k × (x − c)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyMotion {
    pub body: usize,
    pub centroid: [f64; 2],
    pub translation: [f64; 2],
    pub rotation: f64,
}

impl BodyMotion {
    /// The velocity of the point `x` of the body.
    pub fn velocity(&self, x: [f64; 2]) -> [f64; 2] {
        let (c, t, w) = (self.centroid, self.translation, self.rotation);
        [t[0] - w * (x[1] - c[1]), t[1] + w * (x[0] - c[0])]
    }

    /// The largest speed of the points `nodes` (0 without any).
    pub(crate) fn top_speed(&self, nodes: &[[f64; 2]]) -> f64 {
        nodes.iter().fold(0.0f64, |a, &x| {
            let v = self.velocity(x);
            a.max(v[0].hypot(v[1]))
        })
    }
}

/// One moving body of a mechanism in `summary.json` (`mechanism`, and
/// `contact.collapse.motion`): a translation along the unit vector `direction`, or a
/// rotation about the point `centre` (the point that does not move) in the `sense` given;
/// `magnitude` is the largest speed of its boundary nodes, the fastest body's being 1 (the
/// VTK block "mechanism" draws the same velocities).
#[derive(Debug, Clone, Serialize)]
pub struct MechanismBody {
    pub body: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub centre: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 2]>,
    /// "translation" or "rotation".
    pub kind: &'static str,
    pub magnitude: f64,
    /// "clockwise" or "anticlockwise" (rotations only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sense: Option<&'static str>,
}
