//! What the AOVs and the denoiser's guides see of the glTF BSDF: a cheap
//! directional albedo ([`PbrBsdf::albedo`]) and the directions and values of
//! its specular lobes ([`PbrBsdf::guide_lobes`]).

use super::coat::COAT_F0;
use super::fresnel::schlick_grey;
use super::lobes::Local;
use super::params::PbrBsdf;
use super::transmission::refract;
use crate::materials::bsdf::{GUIDE_ALPHA, GuideLobes, unit_range};
use crate::materials::frame::reflect_z;
use crate::materials::sheen;
use glam::Vec3A;

impl PbrBsdf {
    /// A cheap estimate of the directional albedo seen at cosine `cos_o` to the
    /// normal, per channel and clamped to `[0, 1]`, from the same Fresnel terms
    /// at `cos θo` that choose the lobes in [`PbrBsdf::sample`], but in colour:
    /// `m F(c) + (1 − m) (s F_d + (1 − s max(F_d)) c)`, the metal's tint plus the
    /// dielectric's white specular and its diffuse and transmitted parts (both
    /// tinted by `c`). Roughness is ignored (no masking loss), and so is the
    /// interface seen from inside a volume. A smooth metal gives its specular
    /// tint, clear smooth glass about 1.
    pub fn albedo(&self, cos_o: f32) -> Vec3A {
        let cos = cos_o.abs().min(1.0);
        let (m, s) = (self.metallic, self.specular);
        let fd = self.fresnel_air(self.f0(), cos);
        let dielectric = s * fd + (1.0 - s * fd.max_element()) * self.base_tint();
        let mut a = m * self.fresnel_m(cos) + (1.0 - m) * dielectric;
        if self.has_sheen() {
            let e = sheen::albedo(cos, self.sheen_roughness);
            a = a * (1.0 - self.sheen_color.max_element() * e) + self.sheen_color * e;
        }
        if self.coat > 0.0 {
            // About the shading normal (the coat's tilt is ignored here).
            let w = self.coat * schlick_grey(COAT_F0, cos);
            a = a * (1.0 - w) + Vec3A::splat(w);
        }
        if a.is_finite() {
            a.clamp(Vec3A::ZERO, Vec3A::ONE)
        } else {
            Vec3A::ZERO
        }
    }

    /// [`Material::guide_lobes`] of this BSDF: with `α ≤` [`GUIDE_ALPHA`],
    /// the metal's and the dielectric's specular reflection (their Fresnel
    /// terms at `cos θo`, as the smooth lobes of [`PbrBsdf::sample`]) along
    /// the mirror direction, the transmission (refracted through a volume,
    /// straight through a thin wall; none under total internal reflection)
    /// and the diffuse part as the rough albedo; rougher, the whole
    /// [`PbrBsdf::albedo`] is rough.
    ///
    /// A clear coat scales all of these by `1 − w F_c` and adds its own
    /// reflection: along its mirror direction where it is smooth (taking the
    /// reflection's place, with the base's reflected value added), to the
    /// rough part otherwise.
    ///
    /// [`Material::guide_lobes`]: crate::materials::Material::guide_lobes
    pub fn guide_lobes(&self, wo: Vec3A) -> GuideLobes {
        let Some(l) = self.local(wo) else {
            return GuideLobes::NONE;
        };
        let base = self.sheen_guide_lobes(self.base_guide_lobes(wo, &l), &l);
        let Some(coat) = l.coat else {
            return base;
        };
        let under = 1.0 - coat.weight;
        let scaled = |lobe: Option<(Vec3A, Vec3A)>| lobe.map(|(wi, v)| (wi, v * under));
        let w = Vec3A::splat(coat.weight);
        if self.coat_alpha > GUIDE_ALPHA {
            return GuideLobes {
                rough: unit_range(base.rough * under + w),
                reflect: scaled(base.reflect),
                transmit: scaled(base.transmit),
            };
        }
        let wi = l.map(coat.frame.to_world(reflect_z(coat.wo)));
        let reflected = base.reflect.map_or(Vec3A::ZERO, |(_, v)| v * under);
        GuideLobes {
            rough: base.rough * under,
            reflect: GuideLobes::lobe(wi, w + reflected),
            transmit: scaled(base.transmit),
        }
    }

    /// [`PbrBsdf::guide_lobes`] of the material under the sheen and the coat.
    fn base_guide_lobes(&self, wo: Vec3A, l: &Local) -> GuideLobes {
        let l = *l;
        if self.alpha_t() > GUIDE_ALPHA {
            return GuideLobes::rough(self.albedo(wo.z));
        }
        let wo_l = l.wo;
        let cos_o = wo_l.z.min(1.0);
        let (m, s, c) = (self.metallic, self.specular, self.base_color);
        let fd = self.fresnel_d(l.f0, cos_o, l.inside);
        let kd = 1.0 - s * fd.max_element();
        let reflect = m * self.fresnel_m(cos_o) + (1.0 - m) * s * fd;
        let transmit = if self.transmission_scale() > 0.0 {
            let wi = if l.volume {
                refract(wo_l, Vec3A::Z, self.eta(&l))
            } else {
                Some(-wo_l)
            };
            wi.and_then(|wi| GuideLobes::lobe(l.map(wi), c * (self.transmission_scale() * kd)))
        } else {
            None
        };
        GuideLobes {
            rough: unit_range(self.diffuse_tint() * (self.diffuse_scale() * kd)),
            reflect: GuideLobes::lobe(l.map(reflect_z(wo_l)), reflect),
            transmit,
        }
    }
}
