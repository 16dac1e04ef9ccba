//! Seconds per stage of a run, in stage order (`timings.json`, the archive's `/timings`),
//! with the stages timed within a stage (the collapse search's trials) kept apart, so that
//! the total counts every second once.

/// Seconds per stage, in stage order; and the stages timed within a stage, apart.
#[derive(Debug, Clone, Default)]
pub struct Timings(
    pub Vec<(&'static str, f64)>,
    pub Vec<(&'static str, Timings)>,
);

impl Timings {
    /// Adds `seconds` to `stage` (a new stage goes last).
    pub fn add(&mut self, stage: &'static str, seconds: f64) {
        match self.0.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, t)) => *t += seconds,
            None => self.0.push((stage, seconds)),
        }
    }

    /// `seconds` spent in `stage`, of which `inner` itemises the stages within it.
    pub fn add_within(&mut self, stage: &'static str, seconds: f64, inner: Timings) {
        self.add(stage, seconds);
        if !self.1.iter().any(|(s, _)| *s == stage) {
            self.1.push((stage, Timings::default()));
        }
        if let Some((_, t)) = self.1.iter_mut().find(|(s, _)| *s == stage) {
            for (s, v) in inner.0 {
                t.add(s, v);
            }
            for (s, c) in inner.1 {
                t.add_within(s, 0.0, c);
            }
        }
    }

    /// The stages and their total as a JSON object.
    pub fn json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        let mut total = 0.0;
        for (s, t) in &self.0 {
            m.insert((*s).to_string(), serde_json::json!(t));
            total += t;
        }
        m.insert("total".into(), serde_json::json!(total));
        serde_json::Value::Object(m)
    }

    /// timings.json's `within`: per stage with parts, their seconds (a tree).
    pub fn within_json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        for (s, t) in &self.1 {
            let mut v = t.json();
            if !t.1.is_empty() {
                v["within"] = t.within_json();
            }
            m.insert((*s).to_string(), v);
        }
        serde_json::Value::Object(m)
    }
}
