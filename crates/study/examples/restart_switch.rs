//! Does a restart from a checkpoint, then a method switch, give the bits of
//! the same switch in the uninterrupted run? Usage: restart_switch STUDY CASE
//! CKPT_STEP SWITCH_STEP END_STEP CHANGE... (CHANGE: study-file overrides of
//! the switched method, e.g. method.transfer=pic).
use solver::Solver;
use std::path::Path;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let study = Path::new(&a[1]);
    let case = &a[2];
    let n = |i: usize| a[i].parse::<u64>().unwrap();
    let (ckpt, switch, end) = (n(3), n(4), n(5));
    let changes: Vec<String> = a[6..].to_vec();
    let load = |o: &[String]| {
        let s = study::study_file::load(study, o).unwrap();
        s.cases
            .into_iter()
            .find(|c| &c.name == case)
            .unwrap()
            .solver
    };
    let cfg = load(&[]);
    let changed = load(&changes).method;
    let mut straight = Solver::new(cfg.clone()).unwrap();
    let mut bytes = vec![];
    while straight.step_count() < switch {
        if straight.step_count() == ckpt {
            bytes = straight.checkpoint();
        }
        straight.step().unwrap();
    }
    let mut restarted = Solver::new(cfg).unwrap();
    restarted.restore(&bytes).unwrap();
    while restarted.step_count() < switch {
        restarted.step().unwrap();
    }
    println!(
        "at the switch: {:016x} {:016x}",
        straight.state_hash(),
        restarted.state_hash()
    );
    straight.set_method(changed.clone()).unwrap();
    restarted.set_method(changed).unwrap();
    while straight.step_count() < end {
        straight.step().unwrap();
        restarted.step().unwrap();
        if straight.state_hash() != restarted.state_hash() {
            println!("differ from step {}", straight.step_count());
            return;
        }
    }
    println!("same to step {end}: {:016x}", straight.state_hash());
}
