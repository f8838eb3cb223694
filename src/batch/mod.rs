//! Batch processing of shot folders: parallel measurement, summary table, resumable runs.
