//! Case names: each axis value as a short name part (a remedy by its
//! own settings, a pressure in SI units).

use super::*;

/// Readable case-name fragment: `K1.5MPa`, `tait`, `mu0.5`, `dyn`.
pub(super) fn name_part(key: &str, v: &Value) -> String {
    if let Some(remedy) = remedy_descriptor(key) {
        return remedy_name(remedy, v);
    }
    plain_part(key, v)
}

/// `name_part` of a key that is not a remedy's. Names are made from the
/// user's values as written (read raw, by key): a case name never changes
/// with a default or a typed form.
fn plain_part(key: &str, v: &Value) -> String {
    let last = key.rsplit('.').next().unwrap_or(key);
    match (last, v) {
        ("K", Value::Float(_) | Value::Integer(_)) => format!("K{}", si_pascal(as_f64(v))),
        ("viscosity", _) => format!("mu{}", as_f64(v)),
        ("coefficient", Value::Float(_) | Value::Integer(_)) => format!("B{:e}", as_f64(v)),
        ("cell", Value::Float(_)) => format!("h{}cm", 100.0 * as_f64(v)),
        ("no_slip", Value::Array(walls)) if walls.is_empty() => "slip".into(),
        ("no_slip", Value::Array(walls)) => {
            let names: Vec<String> = walls.iter().map(|w| name_part("", w)).collect();
            format!("noslip-{}", names.join("-"))
        }
        ("dt", Value::String(s)) if s == "dynamic" => "dyn".into(),
        // An initial flow by its kind and mode: `tg-m2`, `shear`, `wave-m1`.
        ("flow", Value::Table(t)) => {
            let kind = match t.get("kind").and_then(Value::as_str) {
                Some("taylor_green") => "tg",
                Some("shear_wave") => "shear",
                Some("standing_wave") => "wave",
                Some("grid_seed") => "seed",
                _ => "flow",
            };
            // The grid seed's share tells a halved seed from the full one.
            let kind = match t.get("share") {
                Some(share) => format!("{kind}{}", as_f64(share)),
                None => kind.to_string(),
            };
            match t.get("mode") {
                Some(m) => format!("{kind}-m{}", as_f64(m)),
                None => kind,
            }
        }
        // Bodies that differ by their flows, by those, each after its
        // uniform velocity when it has one (`U1x0_seed-m5`).
        ("body", Value::Array(bodies)) if bodies.iter().all(|b| b.get("flow").is_some()) => {
            let flows: Vec<String> = bodies
                .iter()
                .filter_map(|b| {
                    let flow = plain_part("flow", b.get("flow")?);
                    Some(match b.get("velocity") {
                        Some(u) => format!("{}_{flow}", plain_part("U", u)),
                        None => flow,
                    })
                })
                .collect();
            flows.join("+")
        }
        // Bodies without flows, by their rectangles' sizes (`body0.3x0.6`).
        ("body", Value::Array(bodies)) if bodies.iter().all(|b| body_rect(b).is_some()) => bodies
            .iter()
            .filter_map(body_rect)
            .map(|r| format!("body{}x{}", size(r[2] - r[0]), size(r[3] - r[1])))
            .collect::<Vec<_>>()
            .join("+"),
        (_, Value::String(s)) => s.clone(),
        // A table that changes nothing: the axis's reference value.
        (_, Value::Table(t)) if t.is_empty() => "base".into(),
        (_, Value::Boolean(true)) => last.to_string(),
        (_, Value::Boolean(false)) => format!("no_{last}"),
        (_, Value::Table(t)) => t
            .iter()
            .map(|(k, v)| name_part(k, v))
            .collect::<Vec<_>>()
            .join("-"),
        ("gamma", _) => format!("g{}", as_f64(v)),
        // A list of numbers (a box's size): `box0.8x0.6`, no brackets or
        // spaces in a folder name.
        (_, Value::Array(xs))
            if !xs.is_empty() && xs.iter().all(|x| x.is_float() || x.is_integer()) =>
        {
            let parts: Vec<String> = xs.iter().map(|x| as_f64(x).to_string()).collect();
            format!("{last}{}", parts.join("x"))
        }
        (_, other) => format!("{last}{other}"),
    }
}

/// A body's rectangle, read typed.
fn body_rect(body: &Value) -> Option<[f64; 4]> {
    #[derive(serde::Deserialize)]
    struct Body {
        rect: [f64; 4],
    }
    body.clone().try_into::<Body>().ok().map(|b| b.rect)
}

/// A length as a name shows it (round-off of a difference dropped).
fn size(d: f64) -> f64 {
    (d * 1e9).round() / 1e9
}

/// The remedy a key names (`method.j_bar`, or `j_bar` inside a method table).
fn remedy_descriptor(key: &str) -> Option<&'static Descriptor> {
    let last = match key.rsplit_once('.') {
        Some(("method", last)) => last,
        Some(_) => return None,
        None => key,
    };
    DESCRIPTORS.iter().copied().find(|d| d.key == last)
}

/// A remedy's fragment, written as its old flat keys were (so names do not
/// change with the keys): `j_bar1.0-linear`, `shift_time0.02`, `f_reset`;
/// off (`false`) as the old zero or `no_` form.
fn remedy_name(d: &Descriptor, v: &Value) -> String {
    let head = |main: Option<&Value>| match d.main {
        Some((setting, default)) => {
            let value = main.cloned().unwrap_or(Value::Float(default));
            plain_part(main_name(d, setting), &value)
        }
        None => plain_part(d.key, &Value::Boolean(true)),
    };
    match v {
        Value::Boolean(false) => match d.main {
            Some((setting, _)) => plain_part(main_name(d, setting), &Value::Float(0.0)),
            None => plain_part(d.key, &Value::Boolean(false)),
        },
        Value::Table(t) => {
            let main = d.main.and_then(|(setting, _)| t.get(setting));
            let mut parts = vec![head(main)];
            for (k, value) in t {
                if d.main.is_some_and(|(setting, _)| setting == k) {
                    continue;
                }
                parts.push(plain_part(d.old_key(k), value));
            }
            parts.join("-")
        }
        _ => head(None),
    }
}

/// The main setting's name in case names: its old flat key, or the
/// remedy's own key when it never had one (`grid_damping5.0`).
fn main_name(d: &Descriptor, setting: &str) -> &'static str {
    match d.old_keys.iter().find(|(s, _)| *s == setting) {
        Some((_, old)) => old,
        None => d.key,
    }
}

fn as_f64(v: &Value) -> f64 {
    match v {
        Value::Float(f) => *f,
        Value::Integer(i) => *i as f64,
        _ => f64::NAN,
    }
}

fn si_pascal(p: f64) -> String {
    let (scale, unit) = if p >= 1e9 {
        (1e9, "GPa")
    } else if p >= 1e6 {
        (1e6, "MPa")
    } else if p >= 1e3 {
        (1e3, "kPa")
    } else {
        (1.0, "Pa")
    };
    format!("{}{unit}", (p / scale * 1e6).round() / 1e6)
}
