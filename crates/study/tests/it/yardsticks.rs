//! The yardsticks that see compression and energy gained, end to end: the
//! sound wave's frequency and a damper that acts on compression, and a
//! planted energy source in a slosh that the pump flag sees while the
//! mode-1 swing does not.

use crate::common::{self, kick, stderr, summary_json};
use study::run::probes::energy_gain::EnergyGainFigures;
use study::run::probes::slosh::SloshFigures;
use study::run::probes::sound_wave::SoundWaveFigures;

const SOUND: &str = r#"
name = "tiny_sound"
[scene]
box = [0.2, 0.04]
cell = 0.01
ppc = 2
t_end = 0.1
gravity = 0.0
initial = "zero_stress"
[[scene.body]]
rect = [0.0, 0.0, 0.2, 0.04]
material = "water"
flow = { kind = "sound_wave", amplitude = 0.001, mode = 1 }
[materials.water]
rho0 = 1000.0
eos = "tait"
K = 1.5e6
viscosity = 0.0
[method]
shape = "bspline2"
transfer = "apic"
scheme = "usl"
cfl = 0.2
dt = "dynamic"
[output]
checkpoint_every = 0
vtk_times = []
[matrix]
"method" = [{ }, { artificial_viscosity = true }]
"#;

fn check<C: study::output::summary::Check>(case: &std::path::Path) -> C {
    let s = summary_json(case);
    serde_json::from_value(s["metrics"]["checks"][C::NAME].clone())
        .unwrap_or_else(|e| panic!("{}: no {}: {e}", case.display(), C::NAME))
}

/// The modern baseline's sound has linear acoustics' frequency within 1 %
/// at h = 1 cm and 1.5 MPa, and damps it far less than artificial
/// viscosity does: the yardstick separates a damper the Taylor-Green
/// vortex cannot see. Both keep their energy's growth below the pump share.
#[test]
fn the_sound_wave_has_its_frequency_and_separates_artificial_viscosity() {
    let dir = common::scratch("yardsticks", "sound");
    let study = dir.join("sound.toml");
    std::fs::write(&study, SOUND).unwrap();
    let out = dir.join("out");
    let o = kick(&[
        "matrix",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let base: SoundWaveFigures = check(&out.join("base"));
    let av: SoundWaveFigures = check(&out.join("artificial_viscosity"));
    let c = (1.5e6f64 / 1000.0).sqrt();
    assert!((base.sound_speed - c).abs() < 1e-9 * c, "{base:?}");
    let error = base.frequency_error.expect("a period");
    assert!(error.abs() < 0.01, "{base:?}");
    let (nu_base, nu_av) = (base.excess_viscosity.unwrap(), av.excess_viscosity.unwrap());
    assert!(nu_base > 0.0 && nu_av > 10.0 * nu_base, "{nu_base} {nu_av}");
    for case in ["base", "artificial_viscosity"] {
        let g: EnergyGainFigures = check(&out.join(case));
        assert_eq!(g.is_pump(), Some(false), "{case}: {g:?}");
        // E(0) = rho U^2 / 4 over the box.
        let e0 = 1000.0 * 1e-6 / 4.0 * 0.2 * 0.04;
        assert!((g.wave_energy / e0 - 1.0).abs() < 0.02, "{case}: {g:?}");
    }
}

const SLOSH: &str = r#"
name = "tiny_slosh"
[scene]
box = [0.4, 0.3]
cell = 0.02
ppc = 2
t_end = 2.0
gravity = 9.81
initial = "hydrostatic"
[[scene.body]]
rect = [0.0, 0.0, 0.4, 0.2]
material = "water"
flow = { kind = "standing_wave", amplitude = 0.005, mode = 1 }
[materials.water]
rho0 = 1000.0
eos = "tait"
K = 1.5e6
viscosity = 0.0
[method]
shape = "bspline2"
transfer = "apic"
scheme = "usl"
cfl = 0.2
dt = "dynamic"
[output]
checkpoint_every = 0
vtk_times = []
"#;

/// A planted energy source that feeds small-scale motion (2 x 2-cell
/// upward patches in the bulk over the last half second) raises the pump
/// flag, while the clean inviscid slosh, which the method damps, does not;
/// the planted run's mode-1 period is the clean one's (a mode-1 measure is
/// blind to the source).
#[test]
fn a_planted_source_of_small_scale_motion_raises_the_pump_flag() {
    let dir = common::scratch("yardsticks", "slosh");
    let mut planted = SLOSH.replace("tiny_slosh", "tiny_slosh_planted");
    for (i, t) in [1.55, 1.65, 1.75, 1.85, 1.95].iter().enumerate() {
        let x = [0.12, 0.28][i % 2];
        planted.push_str(&format!(
            "[[perturb]]\nt = {t}\nplace = \"bulk\"\ncells = 2\nnear = [{x}, 0.1]\nspeed = 0.2\ndirection = \"up\"\n"
        ));
    }
    let mut figures = vec![];
    for (name, text) in [("clean", SLOSH.to_string()), ("planted", planted)] {
        let study = dir.join(format!("{name}.toml"));
        std::fs::write(&study, text).unwrap();
        let out = dir.join(name);
        let o = kick(&[
            "run",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let case = std::fs::read_dir(&out)
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path();
        let gain: EnergyGainFigures = check(&case);
        let slosh: SloshFigures = check(&case);
        figures.push((gain, slosh));
    }
    let ((clean, clean_slosh), (planted, planted_slosh)) = (&figures[0], &figures[1]);
    assert_eq!(clean.is_pump(), Some(false), "{clean:?}");
    assert!(clean.growth.unwrap() < 0.0, "the method damps: {clean:?}");
    assert_eq!(planted.is_pump(), Some(true), "{planted:?}");
    let rise = planted.largest_growth().unwrap() - clean.largest_growth().unwrap().max(0.0);
    assert!(rise > 0.05, "{planted:?}");
    // The transfer takes the patches' energy out: a damper, not a cycle.
    assert!(!planted.is_cycling() && !clean.is_cycling(), "{planted:?}");
    let (a, b) = (
        clean_slosh.period_s.unwrap(),
        planted_slosh.period_s.unwrap(),
    );
    assert!((a / b - 1.0).abs() < 0.02, "mode 1's period: {a} and {b}");
}
