//! `kick inf-sup` end to end: the collocated pair's inf-sup constant on
//! the shipped dam break's box falls in proportion to h (the pair is not
//! stable) where the staggered pair's holds, the no-slip box cannot see the
//! collocated checkerboard, and bad input exits 2.

use crate::common::{self, kick, stderr};
use study::replay::inf_sup::InfSupRow;

#[test]
fn the_collocated_pairs_inf_sup_constant_falls_with_h() {
    let dir = common::scratch("inf_sup", "dam");
    let out = dir.join("out");
    let o = kick(&[
        "inf-sup",
        "studies/pressure_implicit.toml",
        "--cell",
        "0.05",
        "--cell",
        "0.025",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for file in ["inf_sup.json", "inf_sup.parquet", "inf_sup.csv"] {
        assert!(out.join(file).is_file(), "{file}");
    }
    let rows: Vec<InfSupRow> =
        serde_json::from_slice(&std::fs::read(out.join("inf_sup.json")).unwrap()).unwrap();
    // Two pairs, three masks, two sizes.
    assert_eq!(rows.len(), 12);
    let beta = |pair: &str, mask: &str, h: f64| {
        rows.iter()
            .find(|r| r.pair.starts_with(pair) && r.mask == mask && r.h == h)
            .map(|r| r.beta)
            .unwrap()
    };
    for mask in ["box, free slip", "box, no slip", "bodies at t = 0"] {
        let ratio = beta("collocated", mask, 0.05) / beta("collocated", mask, 0.025);
        assert!((1.7..2.3).contains(&ratio), "{mask}: {ratio} {rows:?}");
        // The staggered pair keeps its constant.
        let ratio = beta("staggered", mask, 0.05) / beta("staggered", mask, 0.025);
        assert!((0.9..1.1).contains(&ratio), "{mask}: {ratio} {rows:?}");
    }
    let held = rows
        .iter()
        .find(|r| r.pair.starts_with("collocated") && r.mask == "box, no slip")
        .unwrap();
    assert_eq!(
        (held.kernel, held.checkerboard_quotient),
        (2, 0.0),
        "{held:?}"
    );
    // A cell that does not divide the box.
    let o = kick(&[
        "inf-sup",
        "studies/pressure_implicit.toml",
        "--cell",
        "0.07",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--cell 0.07"), "{}", stderr(&o));
}
