//! Result records: what a solve produces, in plain data that post-processing and the
//! writers read. Nothing here computes.

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
