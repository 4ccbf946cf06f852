//! kick's study runner as a library: study files (`study_file`), running
//! cases and matrices (`run`), what a run writes (`output`), and replays of
//! a run (`replay`: reproducing, explaining and timing it). The `kick`
//! binary (main.rs) is the CLI over it, with the plotted reports
//! (`report`), which read what the library wrote and which the library
//! cannot reach.

pub mod output;
pub mod replay;
pub mod run;
pub mod study_file;
