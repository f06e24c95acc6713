//! The lab's integrators, `flat` (the reflectance ρ of the closest triangle)
//! and `direct` (lab task 3: `ρ ∘ (D + N)`, the point light's irradiance `D`,
//! zero in shadow, plus the ambient term `N`): the scalar code ([`scalar`]),
//! one ray or one packet of rays at a time, and the same in the lanes of AVX2
//! registers for a 4×2 pixel block ([`lanes`]), which must equal it bit for
//! bit.

pub(crate) mod lanes;
pub(crate) mod scalar;
