//! Progress of a long validation: which stage runs and, where it can be counted, how far it is,
//! so a run of ten thousand goals shows counts and an estimate of the time left, not a spinner.

/// Receives the stages of a validation and the items done in each.
pub trait Progress: Sync {
    /// A stage starts: a short phrase, and its number of items when they can be counted.
    fn stage(&self, name: &str, total: Option<u64>);
    /// One more item of the current stage is done; called from any thread.
    fn advance(&self);
    /// A warning about the input (the loader's, one line): worth showing even to a quiet user.
    fn warning(&self, _line: &str) {}
    /// A note about the input: a choice the loader made, what an SRDF left out (one line).
    fn info(&self, _line: &str) {}
    /// Whether the caller wants the run to stop (e.g. Ctrl-C in Python): read before each goal
    /// IK solves and the planner joins, and before the engines; the run then ends with
    /// [`crate::error::Error::Stopped`] and no report.
    fn stopped(&self) -> bool {
        false
    }
}

/// Shows nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {
    fn stage(&self, _name: &str, _total: Option<u64>) {}
    fn advance(&self) {}
}
