//! A case as a value: [`CaseKey`], one value of every axis of a study (level, u space,
//! multiplier, p mass, p space, δ, problem kind); [`Pattern<CaseKey>`](Pattern), the same axes each optional
//! (a run's filter, a scene's expected rates); [`CaseAxes`], one list of values per axis (a
//! scene's `[discretization]`, a run's plan). The three are declared together by one table
//! ([`case_axes!`]): adding an axis is one line there, plus the places that use the new axis
//! (its producer in the study, its name in the field files). The key's names in the field
//! files ([`CaseKey::series_name`], [`CaseKey::case_name`]) have their one home here too.
//!
//! **The problem kind** ([`ProblemKind`], the last axis) decides which axes a key has: a scalar
//! key has them all and is written without `problem` (every scalar results file stays as it was
//! before the axis); an elastic key (the smooth-domain method for elasticity, docs/design.md)
//! is written with `problem = "elasticity"` and without `u_space`, `p_mass`, `p_space`, which
//! the AFW method does not have: in memory such an axis holds a placeholder
//! ([`Unwritten::UNWRITTEN`], or the type's default) that no file, name or message shows.

use crate::problem::{MultiplierSpace, Named, PMass, PSpace, USpace};
use crate::scene::ProblemKind;

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

/// The value an axis holds in a key whose problem kind does not have the axis (and has no
/// default): never written, named or shown ([`CaseKey::entries`] leaves the axis out).
pub trait Unwritten {
    /// The placeholder.
    const UNWRITTEN: Self;
}

impl Unwritten for USpace {
    const UNWRITTEN: USpace = USpace::Continuous;
}

/// Whether a plan's list of problem kinds is the scalar problem's alone: summary.json's and
/// `sdcrack check --json`'s plan then has no `problems` (as before the axis).
fn is_scalar_only(problems: &[ProblemKind]) -> bool {
    problems == [ProblemKind::Scalar]
}

/// The value of an axis that a results file does not write for a key of problem kind `$p`:
/// the type's default for an axis with one (`(default)`), the placeholder ([`Unwritten`]) for an
/// axis that `$p` does not have (`if shown` false); `None` (the axis is required) otherwise.
macro_rules! axis_absent {
    ($p:ident, $ty:ty, if $shown:ident) => {
        (!$p.$shown()).then_some(<$ty as Unwritten>::UNWRITTEN)
    };
    ($p:ident, $ty:ty, $default:ident $(, if $shown:ident)?) => {
        Some(<$ty as Default>::$default())
    };
    ($p:ident, $ty:ty) => {
        None::<$ty>
    };
}

/// Declares [`CaseKey`], [`CasePattern`] and [`CaseAxes`] from one table of axes, in the key's
/// order (summary.json's, and the field files'): `field: Type => plural`, the plural optionally
/// preceded by serde attributes of [`CaseAxes`]' list, followed by `(default)` for an axis a
/// scene may leave out: it then runs the type's `Default` value, which is also what a results
/// file written before the axis existed means; and by `if shown` for an axis that only some
/// problem kinds have: a key is written with it when `shown` (a method of [`ProblemKind`]) holds
/// for its `problem`, and read without it as its default or placeholder ([`Unwritten`]).
macro_rules! case_axes {
    ($( $(#[$doc:meta])* $field:ident : $ty:ty => $(#[$pattr:meta])* $plural:ident
        $(($default:ident))? $(if $shown:ident)? ),+ $(,)?) => {
        /// One case of a study: a value of every axis. summary.json writes it flattened into
        /// the case's entry (with the mesh size `h` after the level), the axes its problem kind
        /// has only ([`CaseKey::entries`]).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct CaseKey {
            $( $(#[$doc])* pub $field: $ty, )+
        }

        impl serde::Serialize for CaseKey {
            /// As [`CaseKey::entries`]: the axes of the key's problem kind, in the key's order.
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.collect_map(self.entries())
            }
        }

        impl<'de> serde::Deserialize<'de> for CaseKey {
            /// The axes as written ([`CaseKey::entries`]); an axis not written takes its default
            /// or, where the key's problem kind does not have it, its placeholder
            /// ([`axis_absent!`]); any other missing axis is an error.
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<CaseKey, D::Error> {
                #[derive(serde::Deserialize)]
                struct Written {
                    $( #[serde(default)] $field: Option<$ty>, )+
                }
                let w = Written::deserialize(d)?;
                let problem = w.problem.unwrap_or_default();
                Ok(CaseKey {
                    $( $field: match w.$field {
                        Some(v) => v,
                        None => axis_absent!(problem, $ty $(, $default)? $(, if $shown)?)
                            .ok_or_else(|| <D::Error as serde::de::Error>::missing_field(
                                stringify!($field),
                            ))?,
                    }, )+
                })
            }
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
            $( $(#[$doc])* $(#[$pattr])* $(#[serde($default = "default_list")])?
               pub $plural: Vec<$ty>, )+
        }

        impl CaseKey {
            /// Each axis' name and value, in the key's order (summary.json's keys of a case,
            /// the attributes of its group in the field files): the axes its problem kind has
            /// (`problem` itself only for a kind other than the scalar one).
            pub fn entries(&self) -> Vec<(&'static str, AxisValue)> {
                let mut entries = Vec::new();
                $( if true $(&& self.problem.$shown())? {
                    entries.push((stringify!($field), self.$field.value()));
                } )+
                entries
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
    /// u space (the scalar problem's only).
    u_space: USpace => u_spaces if has_scalar_axes,
    /// Multiplier space.
    multiplier: MultiplierSpace => multipliers,
    /// p mass of the system solved (a scene's default: the consistent one; the scalar
    /// problem's only).
    p_mass: PMass => p_masses (default) if has_scalar_axes,
    /// p space of the system solved (a scene's default: the paper's continuous p); each runs
    /// with the u spaces it serves ([`PSpace::serves`]; the scalar problem's only).
    p_space: PSpace => p_spaces (default) if has_scalar_axes,
    /// Regularisation parameter δ ≥ 0; a list decreasing.
    delta: f64 => deltas,
    /// The problem kind (a scene's `[problem] kind`; the default: the scalar problem, written
    /// only for another kind).
    problem: ProblemKind => #[serde(skip_serializing_if = "is_scalar_only")] problems (default)
        if is_named_in_keys,
}

impl Keyed for CaseKey {
    type Pattern = CasePattern;
}

impl CaseKey {
    /// The key of an elastic case (the AFW method: no u space, p mass or p space; those axes
    /// hold their placeholders, [`Unwritten`]).
    pub fn elastic(level: u32, multiplier: MultiplierSpace, delta: f64) -> CaseKey {
        CaseKey {
            level,
            u_space: USpace::UNWRITTEN,
            multiplier,
            p_mass: PMass::default(),
            p_space: PSpace::default(),
            delta,
            problem: ProblemKind::Elasticity,
        }
    }

    /// Name of the δ sweep this case belongs to in the field files, e.g. `level3-broken-M1`
    /// (and `level3-broken-M1-lumped` for the lumped p mass, `level3-broken-M1-ptangential` for
    /// the broken-tangential p, `level3-broken-M1-lumped-ptangential` for both; an elastic case
    /// `level3-elasticity-M1star`): the time series `fields/<series>.series.xdmf` whose steps are
    /// the sweep's δ.
    pub fn series_name(&self) -> String {
        if !self.problem.has_scalar_axes() {
            return format!("level{}-{}-{}", self.level, self.problem, self.multiplier);
        }
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
    /// The case in words, for messages: `level 2 broken M1 lumped continuous p δ = 0.01`, an
    /// elastic one `level 2 elasticity M1star δ = 0`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let k = self;
        if !k.problem.has_scalar_axes() {
            let (level, problem, m) = (k.level, k.problem, k.multiplier);
            return write!(f, "level {level} {problem} {m} δ = {}", k.delta);
        }
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

    /// Every case, in the order a study solves them: per problem kind, the scalar problem's
    /// ([`CaseAxes::scalar_keys`]) or the elastic one's ([`CaseAxes::elastic_keys`]).
    pub fn keys(&self) -> Vec<CaseKey> {
        (self.problems.iter())
            .flat_map(|&problem| match problem {
                ProblemKind::Scalar => self.scalar_keys(),
                ProblemKind::Elasticity => self.elastic_keys(),
            })
            .collect()
    }

    /// The scalar problem's cases: level, u space, p space, p mass, δ, multiplier, outermost
    /// first (the loops of [`crate::study::run_study`], which share a level's mesh, a (u, p)
    /// pair's assembly and a δ's factorisation with what is inside).
    pub fn scalar_keys(&self) -> Vec<CaseKey> {
        let mut keys = Vec::with_capacity(self.scalar_count());
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
                                problem: ProblemKind::Scalar,
                            });
                        }
                    }
                }
            }
        }
        keys
    }

    /// The elastic problem's cases: level, δ, multiplier, outermost first (the loops of
    /// [`crate::study::run_elastic_study`]); its lists of the scalar axes are empty.
    pub fn elastic_keys(&self) -> Vec<CaseKey> {
        let mut keys = Vec::with_capacity(self.elastic_count());
        for &level in &self.levels {
            for &delta in &self.deltas {
                for &multiplier in &self.multipliers {
                    keys.push(CaseKey::elastic(level, multiplier, delta));
                }
            }
        }
        keys
    }

    /// Number of cases ([`CaseAxes::keys`]' length).
    pub fn case_count(&self) -> usize {
        (self.problems.iter())
            .map(|problem| match problem {
                ProblemKind::Scalar => self.scalar_count(),
                ProblemKind::Elasticity => self.elastic_count(),
            })
            .sum()
    }

    /// Number of scalar cases: levels × (u space, p space) pairs × multipliers × p masses × δ.
    fn scalar_count(&self) -> usize {
        self.levels.len()
            * self.space_pairs().len()
            * self.multipliers.len()
            * self.p_masses.len()
            * self.deltas.len()
    }

    /// Number of elastic cases: levels × multipliers × δ.
    fn elastic_count(&self) -> usize {
        self.levels.len() * self.multipliers.len() * self.deltas.len()
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
            problem: ProblemKind::Scalar,
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
            problems: vec![ProblemKind::Scalar],
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
                "delta",
                "problem"
            ]
        );
        assert_eq!(s[2].values, ["M0", "M1", "M1star"]);
        assert!(s[0].values.is_empty() && s[5].values.is_empty());
        assert_eq!(s[3].default, Some("consistent"));
        assert_eq!(s[6].values, ["scalar", "elasticity"]);
        assert_eq!(s[6].default, Some("scalar"));
        // a scalar key is written without its problem kind, as before the axis
        let entries: Vec<_> = key().entries();
        assert_eq!(entries.iter().map(|e| e.0).collect::<Vec<_>>(), axes[..6]);
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
        assert_eq!(d.clone().complete().map(|a| a.case_count()), Ok(1));
        assert_eq!(d.problems, Some(vec![ProblemKind::Scalar]));
    }

    /// An elastic case: levels × δ × multipliers, named with its problem kind and without the
    /// scalar axes it does not have.
    #[test]
    fn an_elastic_key_has_its_own_axes_only() {
        let axes = CaseAxes {
            levels: vec![0, 1],
            u_spaces: Vec::new(),
            multipliers: vec![MultiplierSpace::M1Star],
            p_masses: Vec::new(),
            p_spaces: Vec::new(),
            deltas: vec![1e-2, 0.0],
            problems: vec![ProblemKind::Elasticity],
        };
        let keys = axes.keys();
        assert_eq!((keys.len(), axes.case_count()), (4, 4));
        assert_eq!((keys[0].level, keys[0].delta), (0, 1e-2));
        assert_eq!((keys[1].level, keys[1].delta), (0, 0.0));
        assert!(keys.iter().all(|k| k.problem == ProblemKind::Elasticity));
        let k = keys[1];
        let names: Vec<&str> = k.entries().iter().map(|e| e.0).collect();
        assert_eq!(names, ["level", "multiplier", "delta", "problem"]);
        assert_eq!(k.case_name(), "level0-elasticity-M1star-delta0");
        assert_eq!(k.to_string(), "level 0 elasticity M1star δ = 0");
        // (its text in summary.json and the plan's: sdcrack-io's summary tests, which have a JSON
        // crate; the core has none)
        let mut scalar_axes = axes.clone();
        scalar_axes.problems = vec![ProblemKind::Scalar];
        assert_eq!(scalar_axes.case_count(), 0);
    }
}
