# Reference numbers for raylab's Mitsuba BSDF tests
# (src/materials/mitsuba/reference.rs): Mitsuba 3.7.1's own BSDFs in
# scalar_rgb, evaluated and sampled at fixed directions and random numbers.
#
#   python -m venv venv && venv/bin/pip install mitsuba==3.7.1 numpy
#   venv/bin/python tools/mitsuba_bsdf_reference.py > src/materials/mitsuba/reference.rs
#
# (Some Dr.Jit builds want an LLVM even for scalar variants: then
# `apt-get install libllvm19` and set
# DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so.)
import mitsuba as mi
mi.set_variant('scalar_rgb')
import numpy as np

def rgb(v): return {'type': 'rgb', 'value': list(v)}
def n(v): v = np.array(v, float); return list(v / np.linalg.norm(v))

mats = {
 'rc_beckmann': {'type':'roughconductor','distribution':'beckmann','alpha':0.2,
    'eta':rgb([0.2,0.9,1.5]),'k':rgb([3.9,2.4,1.6]),'specular_reflectance':rgb([0.9,0.8,0.7])},
 'rc_ggx_aniso': {'type':'roughconductor','distribution':'ggx','alpha_u':0.1,'alpha_v':0.4,
    'eta':rgb([0.2,0.9,1.5]),'k':rgb([3.9,2.4,1.6])},
 'rd_beckmann': {'type':'roughdielectric','distribution':'beckmann','alpha':0.3,'int_ior':1.5,'ext_ior':1.0,
    'specular_transmittance':rgb([0.9,0.8,0.7])},
 'rd_ggx_aniso': {'type':'roughdielectric','distribution':'ggx','alpha_u':0.2,'alpha_v':0.05,'int_ior':1.33,'ext_ior':1.0},
 'plastic': {'type':'plastic','int_ior':1.49,'ext_ior':1.0,'diffuse_reflectance':rgb([0.6,0.3,0.2]),'nonlinear':True},
 'rp_beckmann': {'type':'roughplastic','distribution':'beckmann','alpha':0.2,'int_ior':1.5,'ext_ior':1.0,
    'diffuse_reflectance':rgb([0.6,0.3,0.2])},
 'rp_ggx': {'type':'roughplastic','distribution':'ggx','alpha':0.3,'int_ior':1.49,'ext_ior':1.0,
    'diffuse_reflectance':rgb([0.6,0.3,0.2]),'specular_reflectance':rgb([0.8,0.8,0.9]),'nonlinear':True},
 'dielectric': {'type':'dielectric','int_ior':1.5,'ext_ior':1.0,'specular_reflectance':rgb([0.9,0.8,0.7])},
 'thin': {'type':'thindielectric','int_ior':1.5,'ext_ior':1.0},
 # Mitsuba's default ext_ior is air, 1.000277, not 1: every BSDF here
 # gives ext_ior 1 so that eta = int_ior.
 'conductor': {'type':'conductor','eta':rgb([0.2,0.9,1.5]),'k':rgb([3.9,2.4,1.6])},
 # Principled: every lobe and parameter (principled's eta is relative
 # already: no ext_ior).
 'pr_default': {'type':'principled'},
 'pr_full': {'type':'principled','base_color':rgb([0.8,0.4,0.2]),'metallic':0.3,'specular':0.6,
    'roughness':0.3,'spec_tint':0.4,'anisotropic':0.5,'sheen':0.6,'sheen_tint':0.5,
    'clearcoat':0.7,'clearcoat_gloss':0.4,'flatness':0.3},
 'pr_trans': {'type':'principled','base_color':rgb([0.9,0.7,0.5]),'spec_trans':0.7,'eta':1.4,
    'roughness':0.25,'metallic':0.1,'anisotropic':0.3,'sheen':0.2,'clearcoat':0.5,'spec_tint':0.2},
 'pr_metal': {'type':'principled','base_color':rgb([0.9,0.6,0.3]),'metallic':1.0,'roughness':0.4,
    'anisotropic':0.8},
 'pr_glass': {'type':'principled','base_color':rgb([1.0,1.0,1.0]),'spec_trans':1.0,'roughness':0.2,
    'eta':1.5},
 'pr_rates': {'type':'principled','base_color':rgb([0.3,0.6,0.9]),'spec_trans':0.3,'clearcoat':1.0,
    'clearcoat_gloss':0.8,'main_specular_sampling_rate':0.5,'clearcoat_sampling_rate':2.0,
    'diffuse_reflectance_sampling_rate':0.7,'specular':0.3,'roughness':0.6},
 'pt_default': {'type':'principledthin'},
 'pt_full': {'type':'principledthin','base_color':rgb([0.7,0.5,0.3]),'spec_trans':0.4,'diff_trans':0.6,
    'eta':1.33,'roughness':0.35,'anisotropic':0.4,'spec_tint':0.3,'sheen':0.5,'sheen_tint':0.4,
    'flatness':0.5},
 'pt_glass': {'type':'principledthin','base_color':rgb([1.0,1.0,1.0]),'spec_trans':1.0,
    'roughness':0.2,'eta':1.5},
 'pt_rates': {'type':'principledthin','base_color':rgb([0.6,0.8,0.4]),'spec_trans':0.2,'diff_trans':1.2,
    'specular_reflectance_sampling_rate':0.5,'specular_transmittance_sampling_rate':2.0,
    'diffuse_reflectance_sampling_rate':0.8,'diffuse_transmittance_sampling_rate':1.5,
    'roughness':0.45,'eta':1.2},
}
wos = [n([0.3,0.2,0.9]), n([-0.6,0.5,0.3]), n([0.2,-0.1,-0.8])]
wis = [n([-0.5,0.1,0.8]), n([0.7,0.6,0.2]), n([-0.2,-0.1,-0.9]), n([0.4,0.3,-0.5])]
us = [(0.1,(0.3,0.7)), (0.9,(0.8,0.2)), (0.5,(0.55,0.45)), (0.02, (0.05, 0.93))]
# The principled BSDFs choose among up to four lobes: more random numbers,
# and for eval also directions near the mirror and the straight-through
# ones of each wo (where their specular lobes are).
us_principled = us + [(0.3,(0.2,0.6)), (0.7,(0.4,0.9)), (0.97,(0.6,0.1)), (0.45,(0.9,0.35)),
                      (0.6,(0.15,0.25)), (0.8,(0.7,0.75))]
def near_specular(wo):
    return [n([-wo[0]+0.05, -wo[1]-0.03, wo[2]]), n([-wo[0]*0.7+0.02, -wo[1]*0.7, -wo[2]]),
            n([-wo[0]*1.2, -wo[1]*1.1+0.04, -wo[2]])]
ctx = mi.BSDFContext()
def row(*vals):
    flat = []
    for v in vals:
        flat += [float(x) for x in (v if hasattr(v, '__len__') else [v])]
    return '    [' + ', '.join('%.8e' % x for x in flat) + '],'
print('//! Mitsuba 3.7.1 (`scalar_rgb`) evaluated at fixed directions: written by')
print('//! `tools/mitsuba_bsdf_reference.py` (see there for the BSDFs). Eval rows:')
print('//! `wo, wi, eval (RGB), pdf`; sample rows: `wo, u_lobe, u, wi, weight (RGB), pdf`')
print('//! (raylab\'s names: Mitsuba\'s `si.wi` is `wo`).')
print()
for name, d in mats.items():
    b = mi.load_dict(d)
    print('/// `%s`: %s' % (name, d['type']))
    print('#[rustfmt::skip]')
    print('pub(super) const %s_EVAL: &[[f32; 10]] = &[' % name.upper())
    principled = d['type'].startswith('principled')
    for wo in wos:
        for wi in wis + (near_specular(wo) if principled else []):
            si = mi.SurfaceInteraction3f(); si.wi = mi.Vector3f(wo)
            e = b.eval(ctx, si, mi.Vector3f(wi)); p = b.pdf(ctx, si, mi.Vector3f(wi))
            print(row(wo, wi, e, p))
    print('];')
    print('/// `%s` samples.' % name)
    print('#[rustfmt::skip]')
    print('pub(super) const %s_SAMPLE: &[[f32; 13]] = &[' % name.upper())
    for wo in wos:
        for (ul, u) in (us_principled if principled else us):
            si = mi.SurfaceInteraction3f(); si.wi = mi.Vector3f(wo)
            bs, w = b.sample(ctx, si, ul, mi.Point2f(u))
            if float(bs.pdf) == 0 or max(abs(float(x)) for x in w) == 0: continue
            print(row(wo, ul, u, bs.wo, w, bs.pdf))
    print('];')
