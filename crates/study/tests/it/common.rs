//! Helpers shared by the end-to-end tests of the `kick` binary and the reports.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (tests run `kick` from there, so `studies/...` resolves).
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Runs the `kick` binary from the repository root.
pub fn kick(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kick"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("kick runs")
}

/// A fresh, empty folder for one test: `kick-PREFIX-PID-NAME` in the temp
/// dir, removed when the test passes (kept for inspection when it fails:
/// each run leaves 100+ MB otherwise).
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

pub fn scratch(prefix: &str, name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("kick-{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A case folder's summary.json as loose JSON (for asserting on the file format itself).
pub fn summary_json(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

/// A two-case matrix of 0.05 s dam breaks (K = 15 and 150 kPa).
pub const SMALL_MATRIX: &str = r#"
[scene]
t_end = 0.05
[[scene.body]]
rect = [0.0, 0.0, 0.2, 0.4]
material = "water"
[materials.water]
K = 1.5e4
[output]
checkpoint_every = 0
[matrix]
"materials.water.K" = [1.5e4, 1.5e5]
"#;
