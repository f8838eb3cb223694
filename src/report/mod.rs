//! Writing results: CSV, JSON summaries and plots, atomically.
