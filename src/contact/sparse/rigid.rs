//! Whether a status holds every body, told from the bodies' rigid motions alone.
//!
//! H of a status is singular exactly where a rigid motion of the bodies without a
//! displacement condition moves no closed row: the bodies' energy vanishes on their rigid
//! modes alone, the open rows' openings follow any motion, and a closed row fixes its
//! relative displacement. With one column per rigid mode (3 per body) and one row per closed
//! row (its relative displacement under each mode, [`Problem::row_rigid`]), the status holds
//! every body iff K = Cᵀ C is positive definite. K has the order of three times the bodies
//! (12 000 on the 64 × 64 wall) and the pattern of the bodies' neighbours, so its
//! factorisation costs a few hundredths of a second, where an exact attempt on a status that
//! leaves a body free fails part-way through a factorisation of H (1.2–3.3 s each on the
//! 64 × 64 wall, 11 times).
//!
//! The test is K − δ diag(K) positive definite with δ = [`MARGIN`]: a rigid motion that no
//! closed row sees is a null vector of K, and makes it indefinite by δ of its diagonal, far
//! above the roundoff of K's entries; bodies that the closed rows hold give K a smallest
//! eigenvalue relative to its diagonal far above δ, unless they are held by rows that lie
//! within about 1e-3 of a body's size of each other (two blocks held at two nodes that
//! close: 4.5e-8). Where the test passes and H is singular all the same, the exact attempt
//! fails as before; where it fails, the proximal form is solved, which a status that holds
//! every body also solves.
//!
//! Measured against the factorisations of H (every exact attempt made, the test beside
//! it): the walls of 28 × 28 and 45 × 45 bricks and the sparse runs of ten shipped scenes
//! agree in every status but two: in `pin_in_hole` one status passed the test and failed
//! the factorisation (attempted, as before), and a block on an incline exactly at its
//! friction angle (`incline_block_slides` at t = 0.5), whose sliding mode no force drives,
//! factored on roundoff pivots where the test finds it free.

use faer::Side;

use crate::contact::problem::Problem;

/// δ of the test: relative to K's diagonal, the smallest eigenvalue below which the closed
/// rows are taken to leave a rigid motion free.
const MARGIN: f64 = 1e-8;

/// The rigid-motion rows of a problem's rows, over the rigid modes of its bodies that have
/// them.
pub(super) struct RigidRows {
    /// Entries of row r at `start[r]..start[r + 1]`: (first column of the body's three
    /// modes, the row's relative displacement under them).
    start: Vec<usize>,
    entries: Vec<(usize, [f64; 3])>,
    /// Rows that can open (a prefix of the rows; the others are bonded, always closed).
    n_open: usize,
    /// Columns of K: three per body with rigid modes that a row touches.
    n: usize,
}

impl RigidRows {
    pub(super) fn new(problem: &Problem) -> RigidRows {
        let rows = (0..problem.rows.len()).map(|r| problem.row_rigid(r));
        RigidRows::from_rows(problem.ops.len(), problem.n_open_rows, rows)
    }

    /// From the rigid-motion rows of each row (per body: its three modes' motion of the
    /// row) over `bodies` bodies, of which the first `n_open` rows can open.
    fn from_rows(
        bodies: usize,
        n_open: usize,
        rows: impl Iterator<Item = Vec<(usize, [f64; 3])>>,
    ) -> RigidRows {
        let mut column = vec![usize::MAX; bodies];
        let mut n = 0;
        let mut start = vec![0];
        let mut entries = Vec::new();
        for row in rows {
            for (b, m) in row {
                if column[b] == usize::MAX {
                    column[b] = n;
                    n += 3;
                }
                entries.push((column[b], m));
            }
            start.push(entries.len());
        }
        // A body with rigid modes that no row touches is free in every status; H's base
        // factor has already refused such a problem, so it is not counted here.
        RigidRows {
            start,
            entries,
            n_open,
            n,
        }
    }

    /// No rigid motion at all (every body held by a displacement condition).
    #[cfg(test)]
    pub(super) fn none() -> RigidRows {
        RigidRows::from_rows(0, 0, std::iter::empty())
    }

    /// Whether the closed rows of the status `open` (over the rows that can open, as H's
    /// factorisation takes it: stick rows already following their pairs) hold every body:
    /// Some(false) where they leave a rigid motion free, so that the status's H is singular
    /// (or where the memory for K's factor cannot be had: the proximal form is then solved,
    /// which solves a status that holds every body too); None where K cannot be assembled.
    pub(super) fn holds(&self, open: &[bool]) -> Option<bool> {
        if self.n == 0 {
            return Some(true);
        }
        let closed = |r: usize| r >= self.n_open || !open[r];
        let k = crate::linalg::triangle_from_entries(self.n, Side::Lower, |sink| {
            for r in (0..self.start.len() - 1).filter(|&r| closed(r)) {
                let e = &self.entries[self.start[r]..self.start[r + 1]];
                for &(cj, mj) in e {
                    for &(ci, mi) in e {
                        for a in 0..3 {
                            for b in 0..3 {
                                let (i, j) = (ci + a, cj + b);
                                if i >= j {
                                    sink(i, j, mi[a] * mj[b]);
                                }
                            }
                        }
                    }
                }
            }
            // Every diagonal entry present, so that a mode no closed row sees is a zero
            // pivot rather than a gap in the pattern.
            for i in 0..self.n {
                sink(i, i, 0.0);
            }
        })?;
        let (symbolic, mut values) = k.into_parts();
        {
            let (cp, ri) = (symbolic.col_ptr(), symbolic.row_idx());
            for c in 0..self.n {
                for q in cp[c]..cp[c + 1] {
                    if ri[q] == c {
                        values[q] -= MARGIN * values[q].abs();
                    }
                }
            }
        }
        let k = faer::sparse::SparseColMat::new(symbolic, values);
        Some(crate::linalg::SparseLlt::new(&k).is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::RigidRows;

    /// What the rigid modes of a body with centroid `c` move the point `x` by along `dir`.
    fn modes(x: [f64; 2], c: [f64; 2], dir: [f64; 2]) -> [f64; 3] {
        let r = [x[0] - c[0], x[1] - c[1]];
        [dir[0], dir[1], -r[1] * dir[0] + r[0] * dir[1]]
    }

    /// Rows of a pair at `x` between body `a` (centroid `ca`; None: the clamped base) and
    /// body `b`: tangential (x) then normal (y), B's motion less A's.
    fn pair(
        x: [f64; 2],
        a: Option<(usize, [f64; 2])>,
        b: (usize, [f64; 2]),
    ) -> [Vec<(usize, [f64; 3])>; 2] {
        [[1.0, 0.0], [0.0, 1.0]].map(|dir| {
            let mut row = vec![(b.0, modes(x, b.1, dir))];
            if let Some((a, ca)) = a {
                let m = modes(x, ca, dir);
                row.push((a, [-m[0], -m[1], -m[2]]));
            }
            row
        })
    }

    /// Block 0 (1 × 1, centroid (0.5, 0.5)) on a clamped base, block 1 on block 0, each
    /// joint a pair at x = 0 and at x = `right`; rows 0–3 the base joint (tangential, normal
    /// at x = 0, then at `right`), rows 4–7 the upper joint.
    fn stack(right: f64) -> RigidRows {
        let (c0, c1) = ([0.5, 0.5], [0.5, 1.5]);
        let mut rows = Vec::new();
        for x in [0.0, right] {
            rows.extend(pair([x, 0.0], None, (0, c0)));
        }
        for x in [0.0, right] {
            rows.extend(pair([x, 1.0], Some((0, c0)), (1, c1)));
        }
        RigidRows::from_rows(2, rows.len(), rows.into_iter())
    }

    fn holds(rows: &RigidRows, open: &[usize]) -> bool {
        let mut o = vec![false; 8];
        for &r in open {
            o[r] = true;
        }
        rows.holds(&o).expect("memory")
    }

    #[test]
    fn the_closed_rows_hold_the_bodies_or_leave_their_rigid_motion_free() {
        let s = stack(1.0);
        assert!(holds(&s, &[]), "every row closed");
        // The upper joint slipping at both ends: block 1 slides along x.
        assert!(!holds(&s, &[4, 6]));
        // The base joint slipping: both blocks slide together.
        assert!(!holds(&s, &[0, 2]));
        // One end of the upper joint open, the other closed: block 1 turns about it.
        assert!(!holds(&s, &[6, 7]));
        // One end slipping, the other sticking: held.
        assert!(holds(&s, &[4]));
        // Both ends open: block 1 is free whatever.
        assert!(!holds(&s, &[4, 5, 6, 7]));
        // Held by a bonded row (past the rows that can open) where the rows that can open
        // leave it free: the upper joint's rows all can open, so a bonded copy of one end
        // holds it against sliding but not against turning about that end.
        let c = ([0.5, 0.5], [0.5, 1.5]);
        let mut rows: Vec<Vec<(usize, [f64; 3])>> = Vec::new();
        for x in [0.0, 1.0] {
            rows.extend(pair([x, 0.0], None, (0, c.0)));
        }
        rows.extend(pair([0.0, 1.0], Some((0, c.0)), (1, c.1)));
        let bonded = RigidRows::from_rows(2, 4, rows.clone().into_iter());
        assert!(
            !bonded.holds(&[false; 4]).expect("memory"),
            "turns about (0, 1)"
        );
        rows.extend(pair([1.0, 1.0], Some((0, c.0)), (1, c.1)));
        let bonded = RigidRows::from_rows(2, 4, rows.into_iter());
        assert!(
            bonded.holds(&[false; 4]).expect("memory"),
            "the upper joint bonded"
        );
        assert!(
            !bonded.holds(&[true; 4]).expect("memory"),
            "the base joint open"
        );
    }

    /// A short lever still holds against turning: the ends of each joint 1e-3 apart give
    /// K's smallest eigenvalue 4.5e-8 relative to its diagonal (numpy), above the margin
    /// 1e-8, and a rotation free about one end is still told apart.
    #[test]
    fn a_short_lever_holds_and_one_end_does_not() {
        let s = stack(1e-3);
        assert!(holds(&s, &[]));
        assert!(holds(&s, &[4]));
        assert!(!holds(&s, &[6, 7]));
    }
}
