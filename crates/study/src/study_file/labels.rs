//! How `kick list` and the reports label a material: each equation of state
//! by its own parameters (docs/physics.md section 2), so a Tait or linear
//! material never shows the power law's gamma. Labels only: case names are
//! made in `study_file` and never change with these.

use solver::eos::tait::TAIT_C;
use solver::{EosKind, Material};

/// The study file's name of an EOS (`power`, `tait`, `linear`).
pub fn eos_name(eos: EosKind) -> &'static str {
    match eos {
        EosKind::Power => "power",
        EosKind::Tait => "tait",
        EosKind::Linear => "linear",
    }
}

/// The EOS's own parameter besides K: gamma for the power law, the fixed
/// constant C for Tait, none for the linear law.
pub fn eos_parameter(eos: EosKind, gamma: f64) -> Option<String> {
    match eos {
        EosKind::Power => Some(format!("gamma={gamma}")),
        EosKind::Tait => Some(format!("C={TAIT_C}")),
        EosKind::Linear => None,
    }
}

/// "power gamma=7", "tait C=0.0894", "linear".
pub fn eos_label(eos: EosKind, gamma: f64) -> String {
    match eos_parameter(eos, gamma) {
        Some(p) => format!("{} {p}", eos_name(eos)),
        None => eos_name(eos).to_string(),
    }
}

/// "power K=15000 gamma=7", then the keys that are set: viscosity (mu),
/// j_res, pressure_floor, shear_modulus, softening_strain.
pub fn material_label(m: &Material) -> String {
    let mut parts = vec![eos_name(m.eos).to_string(), format!("K={}", m.k)];
    parts.extend(eos_parameter(m.eos, m.gamma));
    if m.viscosity != 0.0 {
        parts.push(format!("mu={}", m.viscosity));
    }
    if m.j_res != 1.0 {
        parts.push(format!("j_res={}", m.j_res));
    }
    if let Some(floor) = m.pressure_floor {
        parts.push(format!("pressure_floor={floor}"));
    }
    if m.shear_modulus != 0.0 {
        parts.push(format!("shear_modulus={}", m.shear_modulus));
    }
    if m.softening_strain != 0.0 {
        parts.push(format!("softening_strain={}", m.softening_strain));
    }
    parts.join(" ")
}

/// `material_label` with the material's name in front ("water: ...") when it has one.
pub fn named_material_label(m: &Material) -> String {
    if m.name.is_empty() {
        material_label(m)
    } else {
        format!("{}: {}", m.name, material_label(m))
    }
}

/// The EOS label of a material from the texts of its study keys, as a
/// summary's params hold them (`eos` absent = the power law, `gamma`
/// absent = 7, the defaults). None for an EOS name kick does not know.
pub fn eos_label_of_params(eos: Option<&str>, gamma: Option<&str>) -> Option<String> {
    let default = Material::new(1.0);
    let kind = match eos.filter(|e| !e.is_empty()) {
        None => default.eos,
        Some("power") => EosKind::Power,
        Some("tait") => EosKind::Tait,
        Some("linear") => EosKind::Linear,
        Some(_) => return None,
    };
    let gamma = match gamma.filter(|g| !g.is_empty()) {
        None => default.gamma,
        Some(g) => g.parse().ok()?,
    };
    Some(eos_label(kind, gamma))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_eos_is_labelled_by_its_own_parameters() {
        let power = Material::new(1.5e4);
        assert_eq!(material_label(&power), "power K=15000 gamma=7");
        let tait = Material::tait(1e6);
        assert_eq!(material_label(&tait), "tait K=1000000 C=0.0894");
        let linear = Material {
            eos: EosKind::Linear,
            gamma: 4.0,
            ..Material::new(2e5)
        };
        assert_eq!(material_label(&linear), "linear K=200000");
        let set = Material {
            name: "clay".into(),
            viscosity: 0.1,
            j_res: 1.01,
            pressure_floor: Some(-100.0),
            shear_modulus: 2e5,
            softening_strain: 0.05,
            ..Material::tait(1e6)
        };
        assert_eq!(
            named_material_label(&set),
            "clay: tait K=1000000 C=0.0894 mu=0.1 j_res=1.01 pressure_floor=-100 \
             shear_modulus=200000 softening_strain=0.05"
        );
        assert!(!material_label(&tait).contains("gamma"));
    }

    #[test]
    fn params_texts_read_with_the_defaults() {
        assert_eq!(
            eos_label_of_params(Some("tait"), Some("7")).as_deref(),
            Some("tait C=0.0894")
        );
        assert_eq!(
            eos_label_of_params(Some("power"), Some("4")).as_deref(),
            Some("power gamma=4")
        );
        assert_eq!(
            eos_label_of_params(None, None).as_deref(),
            Some("power gamma=7")
        );
        assert_eq!(
            eos_label_of_params(Some("linear"), Some("")).as_deref(),
            Some("linear")
        );
        assert_eq!(eos_label_of_params(Some("stiff"), None), None);
    }
}
