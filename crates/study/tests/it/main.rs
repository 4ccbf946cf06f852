//! The study crate's integration tests, one binary: the `kick` CLI end to
//! end (runs, matrices, reproduction, explanation, bad input), the
//! two-phase runs, the report in a browser, the yardsticks, and the
//! workspace's module graph.

mod calibrate;
mod cli;
mod common;
mod inf_sup;
mod module_graph;
mod report_browser;
mod run_mixture;
mod slurm;
mod yardsticks;
