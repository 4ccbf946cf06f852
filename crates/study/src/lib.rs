//! kick's study runner as a library: study files, running cases and
//! matrices, checkpoints, tables, reproduction of events and plotted reports.
//! The `kick` binary (main.rs) is a thin CLI over it.

pub mod bench;
pub mod case_checkpoint;
pub mod explain;
pub mod explain_picture;
pub mod labels;
pub mod matrix;
pub mod metrics;
pub mod output_files;
pub mod plot_case;
pub mod plot_common;
pub mod plot_matrix;
pub mod probes;
pub mod report;
pub mod report_ablation;
pub mod report_behaviours;
pub mod report_case;
pub mod report_cases;
pub mod report_data;
pub mod report_heatmaps;
pub mod report_html;
pub mod report_matrix;
pub mod report_matrix_verdict;
pub mod report_mechanisms;
pub mod report_mixture;
pub mod report_refinement;
pub mod report_ringing;
pub mod report_speed;
pub mod report_stability;
pub mod report_verdict;
pub mod report_yardsticks;
pub mod reproduce;
pub mod run_case;
pub mod run_mixture;
pub mod runner;
pub mod snapshot;
pub mod study_file;
pub mod summary;
pub mod tables;
pub mod timeseries;
