//! The registry: from the list of remedy modules, the typed `[method.KEY]`
//! sub-tables (absent = off, `true` = on with the defaults, `false` = off),
//! the refusal of the old flat keys, the generic support checks and the list
//! the solver builds its hooks from.

use super::Check;
use super::{Settings, Supports};
use crate::choices::METHOD_KEYS;
use crate::config_error::ConfigError;
use serde::de::{self, Deserialize, Deserializer, MapAccess, Visitor};
use std::fmt;
use std::marker::PhantomData;

/// What the study crate needs to know of a remedy without its type: its key
/// and the names its settings had as flat keys (case names keep them).
#[derive(Debug)]
pub struct Descriptor {
    /// The `[method.KEY]` sub-table.
    pub key: &'static str,
    /// The setting that carries the remedy's strength, with its default
    /// (named in case names even when the table leaves it out); None for a
    /// plain switch.
    pub main: Option<(&'static str, f64)>,
    /// (setting, old flat key) for every setting that had a flat key.
    pub old_keys: &'static [(&'static str, &'static str)],
}

impl Descriptor {
    /// The old flat key of `setting` (itself when it had none).
    pub fn old_key<'a>(&self, setting: &'a str) -> &'a str {
        self.old_keys
            .iter()
            .find(|(s, _)| *s == setting)
            .map_or(setting, |(_, old)| old)
    }

    /// How to write `old` now, if it is one of this remedy's old flat keys.
    fn replacement(&self, old: &str) -> Option<String> {
        let (setting, _) = self.old_keys.iter().find(|(_, o)| *o == old)?;
        Some(format!("[method.{}] {setting} = ...", self.key))
    }
}

/// A remedy's table: `true` (defaults), `false` (off) or its settings.
pub(super) struct Toggle<T>(pub(super) Option<T>);

impl<'de, T: Deserialize<'de> + Default + Settings> Deserialize<'de> for Toggle<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<T: Default + Settings> V<T> {
            fn old_form<E: de::Error>(&self, value: String) -> E {
                let desc = T::default().descriptor();
                let hint = match desc.main {
                    Some((main, _)) => format!(
                        "write [method.{k}] {main} = {value} (or {k} = true for the defaults)",
                        k = desc.key
                    ),
                    None => format!("write {k} = true or false", k = desc.key),
                };
                E::custom(format!(
                    "old key `{}`: `{value}` is the old flat form; {hint}",
                    desc.key
                ))
            }
        }
        impl<'de, T: Deserialize<'de> + Default + Settings> Visitor<'de> for V<T> {
            type Value = Toggle<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a table of settings, true (the defaults) or false (off)")
            }
            fn visit_bool<E: de::Error>(self, on: bool) -> Result<Toggle<T>, E> {
                Ok(Toggle(on.then(T::default)))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Toggle<T>, E> {
                Err(self.old_form(format!("{v:?}")))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Toggle<T>, E> {
                Err(self.old_form(v.to_string()))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Toggle<T>, E> {
                Err(self.old_form(v.to_string()))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Toggle<T>, E> {
                Err(self.old_form(format!("\"{v}\"")))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Toggle<T>, A::Error> {
                T::deserialize(de::value::MapAccessDeserializer::new(map)).map(|t| Toggle(Some(t)))
            }
        }
        d.deserialize_any(V(PhantomData))
    }
}

/// A key of `[method]` that is neither a method field nor a remedy.
pub(super) fn unknown_key<E: de::Error>(key: &str, remedies: &[&Descriptor]) -> E {
    for desc in remedies {
        if let Some(new) = desc.replacement(key) {
            return E::custom(format!(
                "old key `{key}`: the flat key is gone; write {new}"
            ));
        }
    }
    E::unknown_field(key, METHOD_KEYS_AND_REMEDIES)
}

/// Every key `[method]` accepts (the error message's list).
const METHOD_KEYS_AND_REMEDIES: &[&str] = &{
    const N: usize = METHOD_KEYS.len() + super::REMEDY_KEYS.len();
    let mut all = [""; N];
    let mut i = 0;
    while i < METHOD_KEYS.len() {
        all[i] = METHOD_KEYS[i];
        i += 1;
    }
    let mut k = 0;
    while k < super::REMEDY_KEYS.len() {
        all[i + k] = super::REMEDY_KEYS[k];
        k += 1;
    }
    all
};

/// Wraps an error inside a remedy's table with the remedy's key.
pub(super) fn within<E: de::Error>(key: &str, e: E) -> E {
    E::custom(format!("at `{key}`: {e}"))
}

/// The support checks every remedy gets from its [`Supports`].
pub(crate) fn check_supports(key: &str, sup: &Supports, cfg: &Check) -> Result<(), ConfigError> {
    let refuse = |message: String| {
        Err(ConfigError {
            key: format!("method.{key}"),
            message,
        })
    };
    if !sup.solids && cfg.solids {
        return refuse("is for fluids only so far: a material has shear_modulus > 0".into());
    }
    if !sup.periodic && cfg.periodic.iter().any(|&p| p) {
        return refuse(
            "needs walls on both axes (scene.periodic = [false, false]): it mirrors at walls only"
                .into(),
        );
    }
    if !sup.shapes.is_empty() && !sup.shapes.contains(&cfg.shape) {
        return refuse(needs("method.shape", sup.shapes, &cfg.shape));
    }
    if !sup.transfers.is_empty() && !sup.transfers.contains(&cfg.transfer) {
        return refuse(needs("method.transfer", sup.transfers, &cfg.transfer));
    }
    Ok(())
}

/// "needs KEY = "a" | "b" (got "c")", the choices spelled as in a study file.
fn needs<T: fmt::Debug>(key: &str, allowed: &[T], got: &T) -> String {
    let spell = |v: &T| format!("\"{}\"", format!("{v:?}").to_lowercase());
    let allowed: Vec<String> = allowed.iter().map(spell).collect();
    format!("needs {key} = {} (got {})", allowed.join(" | "), spell(got))
}

/// Declares the remedy modules and, from them, `RemedySettings` (one
/// optional field per remedy, in hook order), its deserializer, the key list
/// and the descriptors.
macro_rules! registry {
    ($($m:ident),* $(,)?) => {
        $(pub mod $m;)*

        /// The `[method.KEY]` sub-tables of the remedies (absent = off).
        #[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
        pub struct RemedySettings {
            $(
                #[serde(skip_serializing_if = "Option::is_none")]
                pub $m: Option<$m::Settings>,
            )*
        }

        /// The remedies' keys, in hook order.
        pub const REMEDY_KEYS: &[&str] = &[$(stringify!($m)),*];

        /// Each remedy's descriptor, in hook order.
        pub static DESCRIPTORS: &[&registry::Descriptor] = &[$(&$m::DESCRIPTOR),*];

        impl RemedySettings {
            /// The remedies switched on, in hook order.
            pub fn active(&self) -> Vec<&dyn Settings> {
                let mut on: Vec<&dyn Settings> = vec![];
                $(if let Some(s) = &self.$m { on.push(s); })*
                on
            }

            /// Every remedy's support checks and own validation.
            pub fn validate(&self, cfg: &Check) -> Result<(), ConfigError> {
                for s in self.active() {
                    registry::check_supports(s.descriptor().key, &s.supports(), cfg)?;
                    s.validate(cfg)?;
                }
                Ok(())
            }

            /// The first remedy that cannot run in a mixture, refused.
            pub fn refuse_in_mixture(&self) -> Result<(), ConfigError> {
                match self.active().into_iter().find(|s| !s.supports().mixtures) {
                    Some(s) => Err(ConfigError {
                        key: format!("method.{}", s.descriptor().key),
                        message: "is for a single phase: in a mixture each phase fills only part of a node and of the space".into(),
                    }),
                    None => Ok(()),
                }
            }
        }

        impl<'de> serde::Deserialize<'de> for RemedySettings {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct V;
                impl<'de> serde::de::Visitor<'de> for V {
                    type Value = RemedySettings;
                    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                        f.write_str("remedy tables")
                    }
                    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<RemedySettings, A::Error> {
                        let mut out = RemedySettings::default();
                        while let Some(key) = map.next_key::<String>()? {
                            match key.as_str() {
                                $(stringify!($m) => {
                                    let t: registry::Toggle<$m::Settings> =
                                        map.next_value().map_err(|e| registry::within(&key, e))?;
                                    out.$m = t.0;
                                })*
                                other => return Err(registry::unknown_key(other, DESCRIPTORS)),
                            }
                        }
                        Ok(out)
                    }
                }
                d.deserialize_map(V)
            }
        }
    };
}

pub(crate) use registry;
