//! Seconds per stage of a run, in stage order (`timings.json`, the archive's `/timings`).

/// Seconds per stage, in stage order.
#[derive(Debug, Clone, Default)]
pub struct Timings(pub Vec<(&'static str, f64)>);

impl Timings {
    /// Adds `seconds` to `stage` (a new stage goes last).
    pub fn add(&mut self, stage: &'static str, seconds: f64) {
        match self.0.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, t)) => *t += seconds,
            None => self.0.push((stage, seconds)),
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
}
