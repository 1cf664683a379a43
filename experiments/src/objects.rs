//! Sample objects by name (in progress: owned by the runner work).
