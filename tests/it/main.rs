//! All integration tests in one binary (one link of the crate instead of one per
//! file): a module per topic, and the shared support modules beside them.

mod batch_stub;
mod csv_support;
mod locate_support;
mod model_ref;
mod patch_shot;
mod raw_support;

mod batch_cli;
mod batch_measure;
mod batch_resume;
mod batch_run;
mod batch_shard;
mod chart_output;
mod chart_sinemtf;
mod exif_jpeg;
mod locate_each_chart;
mod locate_find;
mod locate_mtf;
mod locate_realphoto;
mod locate_refine;
mod locate_refine_roi;
mod locate_simulated;
mod locate_timing;
mod measure_accuracy;
mod measure_cli;
mod measure_model;
mod measure_raw;
mod measure_realscan;
mod measure_simulated;
mod model_apertures;
mod model_cli;
mod model_factors;
mod raw_bad_input;
mod raw_dng;
mod raw_green_balance;
mod raw_orientation;
mod raw_simulated_dng;
mod raw_synthetic_dng;
mod raw_windowed_dng;
mod readme_sample;
mod report_patch_model;
mod simulate_cli;
mod simulate_output;
mod simulate_samples;
mod simulate_truth;
