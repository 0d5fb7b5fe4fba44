//! The experiment's methods. A method is three choices that vary
//! independently — the library's matrix [`Method`], the scene optimizer's
//! [`Search`] and the renderer's [`ShadowLookup`] — so it is a struct of the
//! three, named `method[-search][+lookup]` (`focused`, `optimized-argmin`,
//! `lispsm+spsm`). A new lookup mode of the renderer becomes a method suffix
//! by joining [`ShadowLookup::ALL`]; nothing here lists the combinations.
//!
//! The cascade methods of a sun (`csm`, `sdsm`, `sdsm-lispsm`,
//! `optimized-cascades`, [`CascadeMethod`]) are the fourth choice: where the
//! splits go and how each cascade's matrix is fitted. They are named as the
//! engines name them rather than composed, and only run in an experiment
//! with directional lights and `--cascades N`.

use std::cmp::Ordering;
use std::fmt;

use crate::optimize::SearchStrategy;
use crate::render::{CascadePolicy, ShadowLookup};
use crate::{Method, Parameterization, PsmOptions};

/// Matrix methods in report order (the order of `--methods`' default and of
/// the rows of `configs.csv`).
const MATRICES: [Method; 7] = [
    Method::Normal,
    Method::Focused,
    Method::FocusedSnapped,
    Method::LiSpsm,
    Method::Psm,
    Method::PlaneOptimal,
    Method::Optimized,
];

/// How the scene-optimized matrix searches its optical axis (the other
/// matrix methods have no search).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Search {
    /// The paper's rotation heuristic ([`SearchStrategy::Paper`]).
    #[default]
    Paper,
    /// argmin's Nelder–Mead ([`SearchStrategy::NelderMead`]), named
    /// `-argmin`.
    Argmin,
}

impl Search {
    /// Iteration cap of the Nelder–Mead search.
    pub const ARGMIN_ITERATIONS: u64 = 150;

    /// The optimizer's strategy.
    #[must_use]
    pub fn strategy(self) -> SearchStrategy {
        match self {
            Self::Paper => SearchStrategy::Paper,
            Self::Argmin => SearchStrategy::NelderMead { max_iterations: Self::ARGMIN_ITERATIONS },
        }
    }

    /// The name's suffix (empty for the paper's search).
    fn suffix(self) -> &'static str {
        match self {
            Self::Paper => "",
            Self::Argmin => "-argmin",
        }
    }
}

/// A cascaded sun's method ([`CascadePolicy`]): `K` maps, one per depth
/// slice of the view, each a layer of the renderer's map array.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CascadeMethod {
    /// `csm`: practical (λ = 0.75) splits of the camera range within the
    /// scene, texel-snapped focused maps ([`CascadePolicy::csm`]; Bevy's and
    /// most engines' default).
    Csm,
    /// `sdsm`: logarithmic splits inside the visible depth range of the
    /// analysis readback (Lauritzen 2010), focused maps.
    Sdsm,
    /// `sdsm-lispsm`: SDSM splits, LiSPSM maps.
    SdsmLispsm,
    /// `optimized-cascades`: SDSM splits, each cascade scene-optimized from
    /// the same readback ([`CascadePolicy::optimized`]).
    Optimized,
}

impl CascadeMethod {
    /// Every cascade method in report order.
    pub const ALL: [Self; 4] = [Self::Csm, Self::Sdsm, Self::SdsmLispsm, Self::Optimized];

    /// Name on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Csm => "csm",
            Self::Sdsm => "sdsm",
            Self::SdsmLispsm => "sdsm-lispsm",
            Self::Optimized => "optimized-cascades",
        }
    }

    /// The library method that fits each cascade's matrix.
    #[must_use]
    pub const fn matrix(self) -> Method {
        match self {
            Self::Csm => Method::FocusedSnapped,
            Self::Sdsm => Method::Focused,
            Self::SdsmLispsm => Method::LiSpsm,
            Self::Optimized => Method::Optimized,
        }
    }

    /// The frame loop's policy with `count` cascades per sun.
    #[must_use]
    pub fn policy(self, count: usize) -> CascadePolicy {
        match self {
            Self::Csm => CascadePolicy::csm(count),
            Self::Sdsm => CascadePolicy::sdsm(count, Parameterization::Focused),
            Self::SdsmLispsm => CascadePolicy::sdsm(count, Parameterization::LiSpsm(Default::default())),
            Self::Optimized => CascadePolicy::optimized(count),
        }
    }
}

/// A method of the experiment and the viewer: a matrix method, its search
/// and the shadow lookup its pictures are made with, or a cascade method.
///
/// Written and parsed as its [name](Self::name) (also in `settings.json`).
/// Ordered as the report lists methods: by lookup (in
/// [`ShadowLookup::ALL`]'s order), then matrix method, then search.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(into = "String", try_from = "String")]
pub struct MethodSpec {
    matrix: Method,
    search: Search,
    lookup: ShadowLookup,
    cascade: Option<CascadeMethod>,
}

impl MethodSpec {
    /// `normal`.
    pub const NORMAL: Self = Self::standard(Method::Normal);
    /// `focused`.
    pub const FOCUSED: Self = Self::standard(Method::Focused);
    /// `focused-snapped`.
    pub const FOCUSED_SNAPPED: Self = Self::standard(Method::FocusedSnapped);
    /// `lispsm`.
    pub const LISPSM: Self = Self::standard(Method::LiSpsm);
    /// `psm`.
    pub const PSM: Self = Self::standard(Method::Psm);
    /// `plane-optimal`.
    pub const PLANE_OPTIMAL: Self = Self::standard(Method::PlaneOptimal);
    /// `optimized` (the paper's search).
    pub const OPTIMIZED: Self = Self::standard(Method::Optimized);
    /// `optimized-argmin`.
    pub const OPTIMIZED_ARGMIN: Self =
        Self { matrix: Method::Optimized, search: Search::Argmin, lookup: ShadowLookup::DepthCompare, cascade: None };
    /// `csm`.
    pub const CSM: Self = Self::cascaded(CascadeMethod::Csm);
    /// `sdsm`.
    pub const SDSM: Self = Self::cascaded(CascadeMethod::Sdsm);
    /// `sdsm-lispsm`.
    pub const SDSM_LISPSM: Self = Self::cascaded(CascadeMethod::SdsmLispsm);
    /// `optimized-cascades`.
    pub const OPTIMIZED_CASCADES: Self = Self::cascaded(CascadeMethod::Optimized);
    /// The cascade methods in report order (what `--cascades N` adds to
    /// the default `--methods`).
    pub const CASCADED: [Self; 4] = [Self::CSM, Self::SDSM, Self::SDSM_LISPSM, Self::OPTIMIZED_CASCADES];

    /// Every matrix method and search with the standard lookup, in report
    /// order (the experiment's default `--methods`).
    pub const ALL: [Self; 8] = [
        Self::NORMAL,
        Self::FOCUSED,
        Self::FOCUSED_SNAPPED,
        Self::LISPSM,
        Self::PSM,
        Self::PLANE_OPTIMAL,
        Self::OPTIMIZED,
        Self::OPTIMIZED_ARGMIN,
    ];

    /// `matrix` with the paper's search and the standard lookup.
    const fn standard(matrix: Method) -> Self {
        Self { matrix, search: Search::Paper, lookup: ShadowLookup::DepthCompare, cascade: None }
    }

    /// A cascade method with the standard lookup.
    const fn cascaded(cascade: CascadeMethod) -> Self {
        Self {
            matrix: cascade.matrix(),
            search: Search::Paper,
            lookup: ShadowLookup::DepthCompare,
            cascade: Some(cascade),
        }
    }

    /// `matrix` with the paper's search and the standard lookup.
    #[must_use]
    pub fn new(matrix: Method) -> Self {
        Self::standard(matrix)
    }

    /// The same matrix method with another search. `None` for a method
    /// without a search (every one but [`Method::Optimized`]) asked for
    /// anything but [`Search::Paper`].
    #[must_use]
    pub fn with_search(self, search: Search) -> Option<Self> {
        let searches = self.matrix == Method::Optimized && self.cascade.is_none();
        (searches || search == Search::Paper).then_some(Self { search, ..self })
    }

    /// The same matrix method and search with another lookup.
    #[must_use]
    pub fn with_lookup(self, lookup: ShadowLookup) -> Self {
        Self { lookup, ..self }
    }

    /// The library's matrix method (of each cascade, for a cascade method).
    #[must_use]
    pub fn matrix(self) -> Method {
        self.matrix
    }

    /// The cascade method (`None` for a method with one map per light).
    #[must_use]
    pub fn cascade(self) -> Option<CascadeMethod> {
        self.cascade
    }

    /// The scene optimizer's search (always [`Search::Paper`] for the other
    /// methods).
    #[must_use]
    pub fn search(self) -> Search {
        self.search
    }

    /// The shadow lookup of its camera pass (and, for the scene-optimized
    /// method, of its frame loop's analysis bits).
    #[must_use]
    pub fn lookup(self) -> ShadowLookup {
        self.lookup
    }

    /// The parameterization a fixed method solves, with PSM's near plane at
    /// `nearest_view_depth` (what a depth readback supplies); `None` for
    /// the scene-optimized method, which runs a frame loop instead, and for
    /// every cascade method (see [`cascade`](Self::cascade)).
    #[must_use]
    pub fn parameterization(self, nearest_view_depth: Option<f64>) -> Option<Parameterization> {
        if self.cascade.is_some() {
            return None;
        }
        Some(match self.matrix {
            Method::Normal => Parameterization::Normal,
            Method::Focused => Parameterization::Focused,
            Method::FocusedSnapped => Parameterization::FocusedSnapped(Default::default()),
            Method::LiSpsm => Parameterization::LiSpsm(Default::default()),
            Method::Psm => Parameterization::Psm(PsmOptions { min_view_depth: nearest_view_depth }),
            Method::PlaneOptimal => Parameterization::PlaneOptimal(Default::default()),
            _ => return None,
        })
    }

    /// Name on the command line, in the CSVs, reports and file names:
    /// [`Method::name`], `-argmin` for the Nelder–Mead search, `+<lookup>`
    /// for a lookup other than the standard depth compare
    /// ([`ShadowLookup::name`]).
    #[must_use]
    pub fn name(self) -> String {
        self.to_string()
    }

    /// Parses [`name`](Self::name).
    #[must_use]
    pub fn parse(name: &str) -> Option<Self> {
        let (base, lookup) = match name.split_once('+') {
            None => (name, ShadowLookup::DepthCompare),
            Some((base, suffix)) => {
                // The standard lookup has no suffix: one name per method.
                let lookup = ShadowLookup::parse(suffix).filter(|l| *l != ShadowLookup::DepthCompare)?;
                (base, lookup)
            }
        };
        if let Some(cascade) = CascadeMethod::ALL.into_iter().find(|c| c.name() == base) {
            return Some(Self::cascaded(cascade).with_lookup(lookup));
        }
        let (matrix, search) = match base.strip_suffix(Search::Argmin.suffix()) {
            Some(matrix) => (matrix, Search::Argmin),
            None => (base, Search::Paper),
        };
        let matrix = MATRICES.into_iter().find(|m| m.name() == matrix)?;
        Self::new(matrix).with_search(search).map(|m| m.with_lookup(lookup))
    }

    /// Every name [`parse`](Self::parse) takes with the standard lookup,
    /// and the suffixes it takes, for error messages.
    #[must_use]
    pub fn valid_names() -> String {
        let names: Vec<String> = Self::ALL.iter().chain(&Self::CASCADED).map(|m| m.name()).collect();
        let lookups: Vec<&str> =
            ShadowLookup::ALL.iter().filter(|l| **l != ShadowLookup::DepthCompare).map(|l| l.name()).collect();
        format!("{}, each optionally with +{}", names.join(", "), lookups.join(" or +"))
    }

    /// The position in report order (cascade methods after the others).
    fn rank(self) -> (usize, Option<CascadeMethod>, usize, Search) {
        let lookup = ShadowLookup::ALL.iter().position(|l| l.name() == self.lookup.name()).unwrap_or(usize::MAX);
        let matrix = MATRICES.iter().position(|&m| m == self.matrix).unwrap_or(usize::MAX);
        (lookup, self.cascade, matrix, self.search)
    }
}

impl fmt::Display for MethodSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.cascade {
            Some(c) => write!(f, "{}", c.name())?,
            None => write!(f, "{}{}", self.matrix.name(), self.search.suffix())?,
        }
        if self.lookup != ShadowLookup::DepthCompare {
            write!(f, "+{}", self.lookup.name())?;
        }
        Ok(())
    }
}

impl Ord for MethodSpec {
    fn cmp(&self, other: &Self) -> Ordering {
        // Ties of rank (one lookup with different options) fall back to the
        // name so that the order is total and consistent with `Eq` as far
        // as reports can tell methods apart.
        self.rank().cmp(&other.rank()).then_with(|| self.name().cmp(&other.name()))
    }
}

impl PartialOrd for MethodSpec {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl From<MethodSpec> for String {
    fn from(m: MethodSpec) -> Self {
        m.name()
    }
}

impl TryFrom<String> for MethodSpec {
    type Error = String;

    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::parse(&name).ok_or_else(|| format!("unknown method {name:?}; valid methods: {}", Self::valid_names()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_for_every_matrix_search_and_lookup() {
        let mut seen = std::collections::HashSet::new();
        for lookup in ShadowLookup::ALL {
            for m in MethodSpec::ALL.into_iter().chain(MethodSpec::CASCADED) {
                let m = m.with_lookup(lookup);
                let name = m.name();
                assert_eq!(MethodSpec::parse(&name), Some(m), "{name}");
                assert!(seen.insert(name.clone()), "two methods named {name}");
                let json = serde_json::to_string(&m).unwrap();
                assert_eq!(json, format!("{name:?}"));
                assert_eq!(serde_json::from_str::<MethodSpec>(&json).unwrap(), m);
            }
        }
        assert_eq!(seen.len(), (MethodSpec::ALL.len() + MethodSpec::CASCADED.len()) * ShadowLookup::ALL.len());
    }

    #[test]
    fn cascade_methods_are_named_as_the_issue_names_them_and_have_no_search() {
        let names: Vec<String> = MethodSpec::CASCADED.iter().map(|m| m.name()).collect();
        assert_eq!(names, ["csm", "sdsm", "sdsm-lispsm", "optimized-cascades"]);
        for (m, c) in MethodSpec::CASCADED.into_iter().zip(CascadeMethod::ALL) {
            assert_eq!(m.cascade(), Some(c));
            assert_eq!(m.matrix(), c.matrix());
            assert_eq!(m.parameterization(Some(1.0)), None, "{m}");
            assert_eq!(m.with_search(Search::Argmin), None, "{m}");
            assert_eq!(c.policy(3).splits.count, 3);
        }
        assert_eq!(MethodSpec::OPTIMIZED_CASCADES.matrix(), Method::Optimized);
        assert_ne!(MethodSpec::OPTIMIZED_CASCADES, MethodSpec::OPTIMIZED);
        assert_eq!(MethodSpec::parse("optimized-cascades"), Some(MethodSpec::OPTIMIZED_CASCADES));
        for bad in ["optimized-cascades-argmin", "csm-argmin", "sdsm-focused", "cascades"] {
            assert_eq!(MethodSpec::parse(bad), None, "{bad:?}");
        }
        assert!(MethodSpec::valid_names().contains("optimized-cascades"));
        // Report order: every one-map method before the cascade methods.
        let mut all: Vec<MethodSpec> = MethodSpec::CASCADED.iter().rev().chain(&MethodSpec::ALL).copied().collect();
        all.sort();
        let expected: Vec<MethodSpec> = MethodSpec::ALL.into_iter().chain(MethodSpec::CASCADED).collect();
        assert_eq!(all, expected);
    }

    #[test]
    fn names_are_the_library_names_with_suffixes() {
        assert_eq!(MethodSpec::LISPSM.name(), "lispsm");
        assert_eq!(MethodSpec::OPTIMIZED_ARGMIN.name(), "optimized-argmin");
        let spsm = ShadowLookup::ALL[1];
        assert_eq!(MethodSpec::FOCUSED_SNAPPED.with_lookup(spsm).name(), "focused-snapped+spsm");
        assert_eq!(MethodSpec::OPTIMIZED_ARGMIN.with_lookup(spsm).name(), "optimized-argmin+spsm");
        for m in MethodSpec::ALL {
            assert_eq!(m.name().split(['-', '+']).next(), m.matrix().name().split('-').next());
        }
    }

    #[test]
    fn only_the_optimizer_has_a_search_and_unknown_names_are_refused() {
        assert_eq!(MethodSpec::FOCUSED.with_search(Search::Argmin), None);
        for bad in
            ["", "focused-argmin", "focused+", "focused+depth-compare", "optimized+nope", "Focused", "psm+spsm+spsm"]
        {
            assert_eq!(MethodSpec::parse(bad), None, "{bad:?}");
        }
        assert!(serde_json::from_str::<MethodSpec>("\"focused-spsm\"").is_err());
    }

    #[test]
    fn report_order_is_lookup_then_matrix_then_search() {
        let spsm = ShadowLookup::ALL[1];
        let mut all: Vec<MethodSpec> = MethodSpec::ALL.iter().rev().flat_map(|&m| [m.with_lookup(spsm), m]).collect();
        all.sort();
        let expected: Vec<MethodSpec> =
            MethodSpec::ALL.into_iter().chain(MethodSpec::ALL.iter().map(|m| m.with_lookup(spsm))).collect();
        assert_eq!(all, expected);
        assert_eq!(MethodSpec::OPTIMIZED.parameterization(None), None);
        assert!(matches!(
            MethodSpec::PSM.parameterization(Some(2.0)),
            Some(Parameterization::Psm(PsmOptions { min_view_depth: Some(d) })) if d == 2.0
        ));
    }
}
