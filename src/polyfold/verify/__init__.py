"""Independent checks of what polyfold writes: `paths.check_fold_path` re-verifies a folding path
with code that shares nothing with the planners."""
