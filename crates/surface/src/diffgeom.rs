//! Differential geometry of surfaces through [`crate::ParamSurface`].
