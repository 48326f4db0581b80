//! A case as a value: [`CaseKey`], one value of every axis of a study (level, u space,
//! multiplier, p mass, p space, δ); [`Pattern<CaseKey>`](Pattern), the same axes each optional
//! (a run's filter, a scene's expected rates); [`CaseAxes`], one list of values per axis (a
//! scene's `[discretization]`, a run's plan). The three are declared together by one table
//! ([`case_axes!`]): adding an axis is one line there, plus the places that use the new axis
//! (its producer in the study, its name in the field files). The key's names in the field
//! files ([`CaseKey::series_name`], [`CaseKey::case_name`]) have their one home here too.

use crate::problem::{MultiplierSpace, Named, PMass, PSpace, USpace};

/// An axis' value as results files write it: a number, or a name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AxisValue {
    /// An integer (the level).
    Int(u32),
    /// A number (δ).
    Number(f64),
    /// A name of an enum's vocabulary ([`crate::scene_names!`]).
    Name(&'static str),
}

impl serde::Serialize for AxisValue {
    /// As the axis' own type serializes: what summary.json writes for the key's fields.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            AxisValue::Int(v) => s.serialize_u32(v),
            AxisValue::Number(v) => s.serialize_f64(v),
            AxisValue::Name(v) => s.serialize_str(v),
        }
    }
}

/// The values an axis may take: an enum's [`crate::scene_names!`] vocabulary, or a number
/// (level, δ). `sdcrack schema` prints the names with the key.
pub trait AxisValues: Copy {
    /// The names of the values, in their canonical order (empty for a number).
    const NAMES: &'static [&'static str];
    /// This value as results files write it.
    fn value(self) -> AxisValue;
}

impl AxisValues for u32 {
    const NAMES: &'static [&'static str] = &[];
    fn value(self) -> AxisValue {
        AxisValue::Int(self)
    }
}

impl AxisValues for f64 {
    const NAMES: &'static [&'static str] = &[];
    fn value(self) -> AxisValue {
        AxisValue::Number(self)
    }
}

/// A named axis ([`Named`]: the enums of [`crate::scene_names!`]) is written by its name.
impl<T: Named> AxisValues for T {
    const NAMES: &'static [&'static str] = <T as Named>::NAMES;
    fn value(self) -> AxisValue {
        AxisValue::Name(Named::name(self))
    }
}

/// One axis of [`CaseKey`] as `sdcrack schema` prints it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct AxisSchema {
    /// The key's field (summary.json's key of a case).
    pub axis: &'static str,
    /// [`CaseAxes`]' field (summary.json's key in `plan`).
    pub plural: &'static str,
    /// The names of its values ([`AxisValues::NAMES`]; empty for a number).
    pub values: &'static [&'static str],
    /// The value a scene that does not list the axis runs, and a case of a summary written
    /// before the axis existed had: `None` when the axis has always been required.
    pub default: Option<&'static str>,
}

/// A pattern of a key type: its axes, each optional (`None` matches any value).
pub trait Keyed {
    /// The key's pattern type.
    type Pattern;
}

/// The pattern of key type `K` ([`Keyed`]): `Pattern<CaseKey>` is [`CasePattern`].
pub type Pattern<K> = <K as Keyed>::Pattern;

/// The list of a defaulted axis that a summary written before the axis existed means: its
/// type's default alone.
fn default_list<T: Default>() -> Vec<T> {
    vec![T::default()]
}

/// Declares [`CaseKey`], [`CasePattern`] and [`CaseAxes`] from one table of axes, in the key's
/// order (summary.json's, and the field files'): `field: Type => plural`, followed by
/// `(default)` for an axis a scene may leave out: it then runs the type's `Default` value, which
/// is also what a results file written before the axis existed means.
macro_rules! case_axes {
    ($( $(#[$doc:meta])* $field:ident : $ty:ty => $plural:ident $(($default:ident))? ),+ $(,)?) => {
        /// One case of a study: a value of every axis. summary.json writes it flattened into
        /// the case's entry (with the mesh size `h` after the level).
        #[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        pub struct CaseKey {
            $( $(#[$doc])* $(#[serde($default)])? pub $field: $ty, )+
        }

        /// [`CaseKey`]'s axes, each optional: `None` matches every value (a filter's axis not
        /// given, an expected rate's `"*"`).
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct CasePattern {
            $( $(#[$doc])* pub $field: Option<$ty>, )+
        }

        /// The axes of a study's cases, one list of values each: a case is one value of every
        /// axis, except that a p space runs only with the u spaces it serves
        /// ([`PSpace::serves`]). The scene lists them (`[discretization]`), a run's plan
        /// restricts them ([`CasePattern::restrict`]), and summary.json reports the plan's as
        /// `plan` (each value by its name, δ as a number).
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        pub struct CaseAxes {
            $( $(#[$doc])* $(#[serde($default = "default_list")])? pub $plural: Vec<$ty>, )+
        }

        impl CaseKey {
            /// Each axis' name and value, in the key's order (summary.json's keys of a case,
            /// the attributes of its group in the field files).
            pub fn entries(&self) -> Vec<(&'static str, AxisValue)> {
                vec![$( (stringify!($field), self.$field.value()), )+]
            }

            /// The axes, in the key's order, as `sdcrack schema` prints them.
            pub fn schema() -> Vec<AxisSchema> {
                vec![$(AxisSchema {
                    axis: stringify!($field),
                    plural: stringify!($plural),
                    values: <$ty as AxisValues>::NAMES,
                    default: None $(.or(Some(<$ty as Default>::$default().name())))?,
                }),+]
            }
        }

        impl CasePattern {
            /// Whether `key` has this pattern's value on every axis the pattern names.
            pub fn matches(&self, key: &CaseKey) -> bool {
                true $(&& self.$field.is_none_or(|v| v == key.$field))+
            }

            /// `axes` with each axis this pattern names replaced by its one value.
            pub fn restrict(&self, axes: &CaseAxes) -> CaseAxes {
                CaseAxes {
                    $( $plural: self.$field.map_or_else(|| axes.$plural.clone(), |v| vec![v]), )+
                }
            }
        }

        impl CaseAxes {
            /// The lists before a scene is read: each axis a scene may leave out holds its
            /// default ([`default_list`]), the others nothing yet.
            pub fn defaults() -> AxesDraft {
                AxesDraft {
                    $( $plural: None $(.or(Some(vec![<$ty as Default>::$default()])))?, )+
                }
            }
        }

        /// The lists of a scene as it is read ([`CaseAxes::defaults`], then each list the scene
        /// gives): `None` where nothing is known yet.
        #[derive(Clone, Debug, PartialEq)]
        pub struct AxesDraft {
            $( $(#[$doc])* pub $plural: Option<Vec<$ty>>, )+
        }

        impl AxesDraft {
            /// The axes, once every list is known; else the name of the first axis missing.
            pub fn complete(self) -> Result<CaseAxes, &'static str> {
                Ok(CaseAxes {
                    $( $plural: self.$plural.ok_or(stringify!($plural))?, )+
                })
            }
        }
    };
}

case_axes! {
    /// Refinement level ℓ (level ℓ has 2^ℓ·cells cells per direction); a list increasing.
    level: u32 => levels,
    /// u space.
    u_space: USpace => u_spaces,
    /// Multiplier space.
    multiplier: MultiplierSpace => multipliers,
    /// p mass of the system solved (a scene's default: the consistent one).
    p_mass: PMass => p_masses (default),
    /// p space of the system solved (a scene's default: the paper's continuous p); each runs
    /// with the u spaces it serves ([`PSpace::serves`]).
    p_space: PSpace => p_spaces (default),
    /// Regularisation parameter δ ≥ 0; a list decreasing.
    delta: f64 => deltas,
}

impl Keyed for CaseKey {
    type Pattern = CasePattern;
}

impl CaseKey {
    /// Name of the δ sweep this case belongs to in the field files, e.g. `level3-broken-M1`
    /// (and `level3-broken-M1-lumped` for the lumped p mass, `level3-broken-M1-ptangential` for
    /// the broken-tangential p, `level3-broken-M1-lumped-ptangential` for both): the time series
    /// `fields/<series>.series.xdmf` whose steps are the sweep's δ.
    pub fn series_name(&self) -> String {
        let mass = match self.p_mass {
            PMass::Consistent => "",
            PMass::Lumped => "-lumped",
        };
        let space = match self.p_space {
            PSpace::Continuous => "",
            PSpace::BrokenTangential => "-ptangential",
        };
        format!(
            "level{}-{}-{}{mass}{space}",
            self.level, self.u_space, self.multiplier
        )
    }

    /// Name of the case in the field files, e.g. `level3-broken-M1-delta1e-2` (δ = 0 is written
    /// `delta0`): its `/cases/` group in `fields.h5` and `verification.h5`, and its step grid.
    pub fn case_name(&self) -> String {
        format!("{}-delta{}", self.series_name(), delta_text(self.delta))
    }
}

impl std::fmt::Display for CaseKey {
    /// The case in words, for messages: `level 2 broken M1 lumped continuous p δ = 0.01`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let k = self;
        let (level, u, m, pm, ps) = (k.level, k.u_space, k.multiplier, k.p_mass, k.p_space);
        write!(f, "level {level} {u} {m} {pm} {ps} p δ = {}", k.delta)
    }
}

/// The axes of a case that fix its mesh and u dofs: its fields live on the mesh of this key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MeshKey {
    /// Refinement level.
    pub level: u32,
    /// u space (the broken one doubles the crack's interior vertices).
    pub u_space: USpace,
}

impl MeshKey {
    /// Name of the mesh in the field files, e.g. `level3-broken`: its `/meshes/` group.
    pub fn name(&self) -> String {
        format!("level{}-{}", self.level, self.u_space)
    }
}

impl CaseKey {
    /// The key of the mesh this case's fields live on.
    pub fn mesh(&self) -> MeshKey {
        MeshKey {
            level: self.level,
            u_space: self.u_space,
        }
    }
}

/// δ as people write it: the shortest round-trip exponent form (`1e-2`, `1.5e-8`), `0` for zero.
pub fn delta_text(delta: f64) -> String {
    if delta == 0.0 {
        "0".to_string()
    } else {
        format!("{delta:e}")
    }
}

impl CaseAxes {
    /// The (u space, p space) pairs that make cases, u spaces outermost: every pair the p space
    /// serves ([`PSpace::serves`]; a continuous u runs with the continuous p only).
    pub fn space_pairs(&self) -> Vec<(USpace, PSpace)> {
        self.u_spaces
            .iter()
            .flat_map(|&u| {
                self.p_spaces
                    .iter()
                    .filter(move |p| p.serves(u))
                    .map(move |&p| (u, p))
            })
            .collect()
    }

    /// Every case, in the order a study solves them: level, u space, p space, p mass, δ,
    /// multiplier, outermost first (the loops of [`crate::study::run_study`], which share a
    /// level's mesh, a (u, p) pair's assembly and a δ's factorisation with what is inside).
    pub fn keys(&self) -> Vec<CaseKey> {
        let mut keys = Vec::with_capacity(self.case_count());
        for &level in &self.levels {
            for (u_space, p_space) in self.space_pairs() {
                for &p_mass in &self.p_masses {
                    for &delta in &self.deltas {
                        for &multiplier in &self.multipliers {
                            keys.push(CaseKey {
                                level,
                                u_space,
                                multiplier,
                                p_mass,
                                p_space,
                                delta,
                            });
                        }
                    }
                }
            }
        }
        keys
    }

    /// Number of cases: levels × (u space, p space) pairs × multipliers × p masses × δ.
    pub fn case_count(&self) -> usize {
        self.levels.len()
            * self.space_pairs().len()
            * self.multipliers.len()
            * self.p_masses.len()
            * self.deltas.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> CaseKey {
        CaseKey {
            level: 3,
            u_space: USpace::Broken,
            multiplier: MultiplierSpace::M1,
            p_mass: PMass::Lumped,
            p_space: PSpace::BrokenTangential,
            delta: 1e-2,
        }
    }

    #[test]
    fn names_in_the_field_files() {
        let k = key();
        assert_eq!(k.series_name(), "level3-broken-M1-lumped-ptangential");
        assert_eq!(
            k.case_name(),
            "level3-broken-M1-lumped-ptangential-delta1e-2"
        );
        let plain = CaseKey {
            p_mass: PMass::Consistent,
            p_space: PSpace::Continuous,
            delta: 0.0,
            ..k
        };
        assert_eq!(plain.case_name(), "level3-broken-M1-delta0");
    }

    #[test]
    fn a_key_in_words() {
        assert_eq!(
            key().to_string(),
            "level 3 broken M1 lumped broken-tangential p δ = 0.01"
        );
    }

    #[test]
    fn a_pattern_matches_the_axes_it_names_only() {
        let k = key();
        assert!(CasePattern::default().matches(&k));
        let m0 = CasePattern {
            multiplier: Some(MultiplierSpace::M0),
            ..CasePattern::default()
        };
        assert!(!m0.matches(&k));
        let this = CasePattern {
            level: Some(3),
            delta: Some(1e-2),
            p_space: Some(PSpace::BrokenTangential),
            ..CasePattern::default()
        };
        assert!(this.matches(&k));
    }

    #[test]
    fn restrict_keeps_unnamed_axes() {
        let axes = CaseAxes {
            levels: vec![0, 1, 2],
            u_spaces: USpace::ALL.to_vec(),
            multipliers: MultiplierSpace::ALL.to_vec(),
            p_masses: PMass::ALL.to_vec(),
            p_spaces: PSpace::ALL.to_vec(),
            deltas: vec![1.0, 0.0],
        };
        let one = CasePattern {
            level: Some(1),
            u_space: Some(USpace::Continuous),
            ..CasePattern::default()
        }
        .restrict(&axes);
        assert_eq!(one.levels, vec![1]);
        assert_eq!(one.u_spaces, vec![USpace::Continuous]);
        assert_eq!(one.multipliers, axes.multipliers);
        // the continuous u runs with the continuous p only
        assert_eq!(one.case_count(), 3 * 2 * 2);
        assert_eq!(one.keys().len(), one.case_count());
        let all = axes.keys();
        assert_eq!(all.len(), axes.case_count());
        assert!(all.iter().all(|k| k.p_space.serves(k.u_space)));
        // δ inside the p mass, the multiplier innermost
        assert_eq!(
            (all[0].multiplier, all[1].multiplier),
            (MultiplierSpace::M0, MultiplierSpace::M1)
        );
        assert_eq!((all[2].delta, all[3].delta), (1.0, 0.0));
    }

    #[test]
    fn the_schema_lists_the_key_in_its_order_with_names_and_defaults() {
        let s = CaseKey::schema();
        let axes: Vec<_> = s.iter().map(|a| a.axis).collect();
        assert_eq!(
            axes,
            [
                "level",
                "u_space",
                "multiplier",
                "p_mass",
                "p_space",
                "delta"
            ]
        );
        assert_eq!(s[2].values, ["M0", "M1", "M1star"]);
        assert!(s[0].values.is_empty() && s[5].values.is_empty());
        assert_eq!(s[3].default, Some("consistent"));
        let entries: Vec<_> = key().entries();
        assert_eq!(entries.iter().map(|e| e.0).collect::<Vec<_>>(), axes);
        assert_eq!(entries[0].1, AxisValue::Int(3));
        assert_eq!(entries[3].1, AxisValue::Name("lumped"));
        assert_eq!(entries[5].1, AxisValue::Number(1e-2));
        assert_eq!(s[4].default, Some("continuous"));
        assert_eq!(s[1].default, None);
        let mut d = CaseAxes::defaults();
        assert_eq!(d.p_masses, Some(vec![PMass::Consistent]));
        assert_eq!(d.p_spaces, Some(vec![PSpace::Continuous]));
        assert_eq!(d.levels, None);
        assert_eq!(d.clone().complete(), Err("levels"));
        d.levels = Some(vec![0]);
        d.u_spaces = Some(vec![USpace::Broken]);
        d.multipliers = Some(vec![MultiplierSpace::M0]);
        d.deltas = Some(vec![0.0]);
        assert_eq!(d.complete().map(|a| a.case_count()), Ok(1));
    }
}
