//! The bem stage's output: every body assembled and condensed onto its interface unknowns,
//! the hand-over to the contact stage.
//!
//! Place in the flow: `assembly`, `condensation` → **`operators`** → `contact`. The per-body
//! work (the expensive part) is done once by [`prepare`]; the contact problem is built on
//! it, and each body's boundary solution is recovered from it
//! (`condensation::recover`).

use std::time::Instant;

use crate::bem::assembly::{assemble_body, check_single_layer, BodySystem, Unknown};
use crate::bem::condensation::{condense, Condensed};
use crate::bem::quadrature::QuadratureSettings;
use crate::error::Result;
use crate::input::model::Model;
use crate::input::scene::Plane;

/// Every body assembled and condensed (the bem stage's output).
pub struct Operators {
    pub systems: Vec<BodySystem>,
    pub condensed: Vec<Condensed>,
    pub maps: Vec<X0Map>,
    /// Seconds spent assembling and condensing.
    pub assemble_seconds: f64,
    pub condense_seconds: f64,
}

/// Assembles and condenses every body for the loads scaled by `load_factor`. `progress`
/// hears each body's name as it is done (from the worker threads, in any order).
pub fn prepare(
    model: &Model,
    plane: Plane,
    settings: &QuadratureSettings,
    load_factor: f64,
    scene_file: &std::path::Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Operators> {
    let t_start = Instant::now();
    use rayon::prelude::*;
    // Bodies are independent: assembled and condensed in parallel (a wall of many small
    // bricks keeps both cores busy; a large body's assembly is parallel inside too).
    let done: Vec<Result<(BodySystem, Condensed, f64, f64)>> = (0..model.bodies.len())
        .into_par_iter()
        .map(|bi| {
            let body = &model.bodies[bi];
            let t0 = Instant::now();
            let sys = assemble_body(model, bi, plane, settings, load_factor, scene_file)?;
            check_single_layer(&sys, &body.name)?;
            let ta = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            let c = condense(&sys, &body.name)?;
            progress(&body.name);
            Ok((sys, c, ta, t1.elapsed().as_secs_f64()))
        })
        .collect();
    let mut systems = Vec::with_capacity(model.bodies.len());
    let mut condensed = Vec::with_capacity(model.bodies.len());
    let (mut ta, mut tc) = (0.0, 0.0);
    for d in done {
        let (sys, c, a, b) = d?;
        systems.push(sys);
        condensed.push(c);
        ta += a;
        tc += b;
    }
    // Seconds of CPU over the bodies, shared out in proportion to the wall-clock time.
    let wall = t_start.elapsed().as_secs_f64();
    let cpu = (ta + tc).max(f64::MIN_POSITIVE);
    let (ta, tc) = (wall * ta / cpu, wall * tc / cpu);
    let maps = systems.iter().map(X0Map::new).collect();
    Ok(Operators {
        systems,
        condensed,
        maps,
        assemble_seconds: ta,
        condense_seconds: tc,
    })
}

/// Lookup table `(iface, pair, comp, traction) → X0 index` for one body.
pub struct X0Map {
    map: std::collections::HashMap<(usize, usize, usize, bool), usize>,
}

impl X0Map {
    pub fn new(sys: &BodySystem) -> Self {
        let mut map = std::collections::HashMap::new();
        for (i, u) in sys.unknowns[sys.n_x..].iter().enumerate() {
            match *u {
                Unknown::Traction0 {
                    iface, pair, comp, ..
                } => {
                    map.insert((iface, pair, comp, true), i);
                }
                Unknown::Displacement {
                    on: Some((k, j, c)),
                    ..
                } => {
                    map.insert((k, j, c, false), i);
                }
                _ => {}
            }
        }
        X0Map { map }
    }
    pub fn get(&self, iface: usize, pair: usize, comp: usize, traction: bool) -> Option<usize> {
        self.map.get(&(iface, pair, comp, traction)).copied()
    }
}
