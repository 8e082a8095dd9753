//! The flattening methods offered on the command line (`--method`).

use serde::{Deserialize, Serialize};

/// A flattening method. The kebab-case names are the command-line contract.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Minimizes Duncan's isometric distortion δ2 (symmetric Dirichlet), flip-free. The default.
    Isometric,
    /// Minimizes Duncan's conformal distortion δ1 = log(μ1/μ2), flip-free.
    Conformal,
    /// Least-squares conformal maps with a free boundary.
    Lscm,
    /// Duncan's f2: conformal, and locally isometric along the boundary.
    ConformalBoundary,
    /// As-rigid-as-possible (local/global) with a free boundary.
    Arap,
    /// Exact unfolding of a developable surface; refuses a surface that is not developable.
    Developable,
    /// Minimizes Duncan's global distortion δ0 = log(s2/s1).
    Minmax,
    /// Duncan's f1: every boundary edge keeps its length, the interior minimizes Σ(λi − 1)².
    BoundaryIsometric,
    /// The Green strain in the material's grain frame weighted by its stiffness along, across
    /// and in shear (a woven fabric takes its strain on the bias), flip-free; needs a material.
    Orthotropic,
}

impl Method {
    /// Every method, in the order the CLI lists them when a method name is unknown.
    pub const ALL: [Method; 9] = [
        Method::Isometric,
        Method::Conformal,
        Method::Lscm,
        Method::ConformalBoundary,
        Method::Arap,
        Method::Developable,
        Method::Minmax,
        Method::BoundaryIsometric,
        Method::Orthotropic,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Isometric => "isometric",
            Method::Conformal => "conformal",
            Method::Lscm => "lscm",
            Method::ConformalBoundary => "conformal-boundary",
            Method::Arap => "arap",
            Method::Developable => "developable",
            Method::Minmax => "minmax",
            Method::BoundaryIsometric => "boundary-isometric",
            Method::Orthotropic => "orthotropic",
        }
    }

    /// Parses a command-line name.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == s)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
