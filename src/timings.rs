//! Seconds per stage of a run, in stage order (`timings.json`, the archive's `/timings`),
//! with the stages timed within a stage (the collapse search's trials) kept apart, so that
//! the total counts every second once.

use std::collections::BTreeMap;

use serde::Serialize;

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
    pub(crate) fn add_within(&mut self, stage: &'static str, seconds: f64, inner: Timings) {
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

    /// The stages and their total: `timings.json`'s `stages`.
    pub fn seconds(&self) -> StageSeconds {
        StageSeconds {
            stages: self.0.clone(),
            total: self.0.iter().fold(0.0, |sum, (_, t)| sum + t),
            within: None,
        }
    }

    /// `timings.json`'s `within`: per stage with parts, their seconds (a tree).
    pub fn within(&self) -> BTreeMap<&'static str, StageSeconds> {
        self.1
            .iter()
            .map(|(s, t)| {
                let mut seconds = t.seconds();
                seconds.within = (!t.1.is_empty()).then(|| t.within());
                (*s, seconds)
            })
            .collect()
    }
}

/// The whole of `timings.json`: the date of the run and the seconds of its stages.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct TimingsFile<'a> {
    /// UTC time the run's record was made, ISO 8601.
    pub created: &'a str,
    /// Every stage's seconds and their total.
    pub stages: StageSeconds,
    /// Per stage timed in parts (the collapse search's trials), the parts' seconds.
    pub within: BTreeMap<&'static str, StageSeconds>,
}

/// One level of stages: each stage's seconds, their `total` and, where a stage has parts,
/// `within`. Written as one object whose keys (the stages' names, `total`, `within`) are
/// sorted, as `timings.json` has always been written.
#[derive(Debug, Clone)]
pub struct StageSeconds {
    /// Seconds per stage, in stage order.
    pub stages: Vec<(&'static str, f64)>,
    pub total: f64,
    /// The parts of the stages timed in parts; `None` (no key) when no stage has any.
    pub within: Option<BTreeMap<&'static str, StageSeconds>>,
}

/// A value of a [`StageSeconds`] object.
#[derive(Serialize)]
#[serde(untagged)]
enum StageEntry<'a> {
    Seconds(f64),
    Within(&'a BTreeMap<&'static str, StageSeconds>),
}

impl Serialize for StageSeconds {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // A later key replaces an earlier one of the same name, as in a map.
        let mut entries: BTreeMap<&str, StageEntry> = self
            .stages
            .iter()
            .map(|(n, t)| (*n, StageEntry::Seconds(*t)))
            .collect();
        entries.insert("total", StageEntry::Seconds(self.total));
        if let Some(w) = &self.within {
            entries.insert("within", StageEntry::Within(w));
        }
        s.collect_map(entries)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every object of `timings.json` is written with its keys sorted, `total` and `within`
    /// among the stages' names, at every depth; the top level's stages without `within`.
    #[test]
    fn keys_are_sorted_with_total_and_within_among_the_stages() {
        let mut trial = Timings::default();
        trial.add("b", 1.0);
        let mut search = Timings::default();
        search.add("write", 0.5);
        search.add("assemble", 0.25);
        search.add_within("trial", 1.0, trial);
        let mut t = Timings::default();
        t.add("read", 1.0);
        t.add_within("collapse_search", 2.0, search);
        let file = TimingsFile {
            created: "2025-01-31T12:00:00Z",
            stages: t.seconds(),
            within: t.within(),
        };
        let text = serde_json::to_string(&file).unwrap_or_default();
        assert_eq!(
            text,
            "{\"created\":\"2025-01-31T12:00:00Z\",\
             \"stages\":{\"collapse_search\":2.0,\"read\":1.0,\"total\":3.0},\
             \"within\":{\"collapse_search\":{\"assemble\":0.25,\"total\":1.75,\"trial\":1.0,\
             \"within\":{\"trial\":{\"b\":1.0,\"total\":1.0}},\"write\":0.5}}}"
        );
        let empty = Timings::default();
        let text = serde_json::to_string(&empty.seconds()).unwrap_or_default();
        assert_eq!(text, "{\"total\":0.0}");
    }
}
