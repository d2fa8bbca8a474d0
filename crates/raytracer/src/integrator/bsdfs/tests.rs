//! Statistical and analytic tests of every BSDF (as Mitsuba's and pbrt's BSDF tests):
//! (a) a chi-square test of `sample` against `pdf` over a sphere grid, (b) `weight = f cos / pdf`
//! for non-delta samples, (c) white furnaces, (d) reciprocity, (e) the pdf's integral.
//!
//! Every test draws from fixed seeds, so it is deterministic. Each chi-square test rejects at a
//! significance of 1e-4, so that over the ~140 (variant, direction) pairs the family-wise
//! false-alarm rate (over random seeds) is about 1.4% (Sidak), as Mitsuba's BSDF tests do.

use std::f64::consts::{PI, TAU};

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::special::erfc;
use super::*;
use crate::material::{Coating, Distribution, Interface, Metal, Microfacet, Principled, PrincipledThin};

/// Significance of each chi-square test.
const SIGNIFICANCE: f64 = 1e-4;

fn c(v: f64) -> Param {
    Param::scalar(v)
}

fn rgb(r: f64, g: f64, b: f64) -> Param {
    Param::Constant(DVec3::new(r, g, b))
}

fn build(m: &Material) -> PhysicalBsdf {
    PhysicalBsdf::new(m, &mut |p| match p {
        Param::Constant(v) => *v,
        Param::Texture(_) => DVec3::splat(0.5),
    })
}

fn interface(int_ior: f64) -> Interface {
    Interface { int_ior, ext_ior: 1.000_277, specular_reflectance: c(1.0), specular_transmittance: c(1.0) }
}

fn microfacet(distribution: Distribution, au: f64, av: f64, sample_visible: bool) -> Microfacet {
    Microfacet { distribution, alpha_u: c(au), alpha_v: c(av), sample_visible }
}

fn gold() -> Metal {
    Metal {
        eta: DVec3::new(0.143_119, 0.374_957, 1.442_479),
        k: DVec3::new(3.983_160, 2.385_721, 1.603_215),
        specular_reflectance: c(1.0),
    }
}

fn coating(d: Param) -> Coating {
    Coating {
        diffuse_reflectance: d,
        specular_reflectance: c(1.0),
        int_ior: 1.49,
        ext_ior: 1.000_277,
        nonlinear: false,
    }
}

/// A unit direction from spherical angles (degrees).
fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

// ---------------------------------------------------------------- chi-square

const N_THETA: usize = 16;
const N_PHI: usize = 32;

fn cell_of(w: DVec3) -> usize {
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += TAU;
    }
    let i = ((theta / PI * N_THETA as f64) as usize).min(N_THETA - 1);
    let j = ((phi / TAU * N_PHI as f64) as usize).min(N_PHI - 1);
    i * N_PHI + j
}

/// The pdf integrated over every cell: the midpoint rule, `sub x sub` points per cell, and
/// four times finer in theta in the two bands beside the horizon (where refraction through
/// steep facets piles directions up) and at the poles.
fn cell_integrals(b: &PhysicalBsdf, wo: DVec3, sub: usize) -> Vec<f64> {
    let mut out = vec![0.0; N_THETA * N_PHI];
    let dp = TAU / (N_PHI * sub) as f64;
    for bin in 0..N_THETA {
        let fine = matches!(bin, 0 | 1)
            || bin + 2 >= N_THETA
            || bin + 2 == N_THETA / 2
            || bin == N_THETA / 2
            || bin + 1 == N_THETA / 2;
        let st_count = if fine { sub * 4 } else { sub };
        let dt = PI / N_THETA as f64 / st_count as f64;
        for i in 0..st_count {
            let theta = bin as f64 * PI / N_THETA as f64 + (i as f64 + 0.5) * dt;
            let (st, ct) = theta.sin_cos();
            for j in 0..N_PHI * sub {
                let phi = (j as f64 + 0.5) * dp;
                let w = DVec3::new(st * phi.cos(), st * phi.sin(), ct);
                out[bin * N_PHI + j / sub] += b.pdf(wo, w) * st * dt * dp;
            }
        }
    }
    out
}

/// The upper tail of the chi-square distribution with `dof` degrees of freedom (Wilson and
/// Hilferty's normal approximation, good to a few percent of p for `dof` above 30).
fn chi2_tail(stat: f64, dof: f64) -> f64 {
    let h = 2.0 / (9.0 * dof);
    let z = ((stat / dof).cbrt() - (1.0 - h)) / h.sqrt();
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

struct Chi2 {
    p: f64,
    integral: f64,
    non_delta: usize,
}

/// Draws `n` samples for `wo` and compares their histogram (and the count of delta or failed
/// samples) with the pdf's integrals; the cells with expected counts below 5 are pooled.
fn chi2(b: &PhysicalBsdf, wo: DVec3, n: usize, seed: u64, sub: usize) -> Chi2 {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut observed = vec![0.0; N_THETA * N_PHI];
    let mut non_delta = 0;
    for _ in 0..n {
        let (u, u1, u2) = (rng.random::<f64>(), rng.random::<f64>(), rng.random::<f64>());
        if let Some(s) = b.sample(wo, u, u1, u2)
            && !s.delta
        {
            observed[cell_of(s.wi)] += 1.0;
            non_delta += 1;
        }
    }
    let expected: Vec<f64> = cell_integrals(b, wo, sub).iter().map(|p| p * n as f64).collect();
    let integral = expected.iter().sum::<f64>() / n as f64;
    // The remainder: delta outcomes and no sample at all.
    let mut cells: Vec<(f64, f64)> = observed.into_iter().zip(expected).collect();
    cells.push(((n - non_delta) as f64, (n as f64 * (1.0 - integral)).max(0.0)));
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let mut stat = 0.0;
    let mut k = 0;
    for (o, e) in cells {
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            stat += (o - e) * (o - e) / e;
            k += 1;
        }
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        k += 1;
    } else if pool_o > 0.0 {
        // Samples where the pdf says there can be none.
        return Chi2 { p: 0.0, integral, non_delta };
    }
    Chi2 { p: chi2_tail(stat, (k - 1).max(1) as f64), integral, non_delta }
}

/// The variants the statistical tests run over, with the directions they are viewed from.
fn variants() -> Vec<(String, Material, Vec<DVec3>)> {
    let front = vec![dir(0.0, 0.0), dir(30.0, 20.0), dir(75.0, 200.0)];
    let both = vec![dir(10.0, 0.0), dir(60.0, 120.0), dir(85.0, 300.0), dir(130.0, 40.0), dir(170.0, 250.0)];
    let mut out: Vec<(String, Material, Vec<DVec3>)> = vec![
        ("diffuse".into(), Material::Diffuse { reflectance: rgb(0.8, 0.5, 0.2) }, front.clone()),
        ("conductor".into(), Material::Conductor(gold()), front.clone()),
        ("dielectric".into(), Material::Dielectric(interface(1.5046)), both.clone()),
        ("thindielectric".into(), Material::ThinDielectric(interface(1.5046)), both.clone()),
        ("plastic".into(), Material::Plastic(coating(rgb(0.6, 0.3, 0.1))), front.clone()),
        (
            "plastic nonlinear".into(),
            Material::Plastic(Coating { nonlinear: true, ..coating(c(0.9)) }),
            front.clone(),
        ),
    ];
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        for (au, av, vis) in
            [(0.3, 0.3, true), (0.15, 0.5, true), (0.9, 0.9, true), (0.3, 0.3, false), (0.2, 0.6, false)]
        {
            let mf = microfacet(kind, au, av, vis);
            let tag = format!("{kind:?} {au}x{av} visible={vis}");
            out.push((
                format!("roughconductor {tag}"),
                Material::RoughConductor { metal: gold(), microfacet: mf.clone() },
                front.clone(),
            ));
            out.push((
                format!("roughdielectric {tag}"),
                Material::RoughDielectric { interface: interface(1.5046), microfacet: mf.clone() },
                both.clone(),
            ));
            if au == av {
                out.push((
                    format!("roughplastic {tag}"),
                    Material::RoughPlastic { coating: coating(rgb(0.5, 0.7, 0.2)), microfacet: mf },
                    front.clone(),
                ));
            }
        }
    }
    for name in [
        "principled_default",
        "principled_full",
        "principled_glass",
        "principled_metal",
        "principledthin_default",
        "principledthin_full",
        "principledthin_clear",
    ] {
        out.push((format!("principled variant {name}"), mitsuba_material(name), both.clone()));
    }
    // Low sampling rates of the specular lobes and a glossy clearcoat.
    out.push((
        "principled variant rates".into(),
        Material::Principled(Principled {
            spec_trans: c(0.5),
            clearcoat: c(1.0),
            clearcoat_gloss: c(0.8),
            specular_sampling_rate: 0.3,
            clearcoat_sampling_rate: 2.0,
            diffuse_sampling_rate: 0.5,
            ..principled_defaults()
        }),
        both.clone(),
    ));
    out.push((
        "principled variant thin rates".into(),
        Material::PrincipledThin(PrincipledThin {
            spec_trans: c(0.5),
            diff_trans: c(1.0),
            anisotropic: c(0.8),
            eta: c(1.2),
            specular_reflectance_sampling_rate: 0.5,
            specular_transmittance_sampling_rate: 2.0,
            diffuse_reflectance_sampling_rate: 1.0,
            diffuse_transmittance_sampling_rate: 0.25,
            ..thin_defaults()
        }),
        both.clone(),
    ));
    let rough =
        Material::RoughConductor { metal: gold(), microfacet: microfacet(Distribution::Ggx, 0.4, 0.4, true) };
    out.push((
        "twosided(diffuse, roughconductor)".into(),
        Material::TwoSided {
            front: Box::new(Material::Diffuse { reflectance: c(0.7) }),
            back: Box::new(rough.clone()),
        },
        both.clone(),
    ));
    out.push((
        "mask(0.3, roughplastic)".into(),
        Material::Mask {
            opacity: c(0.3),
            material: Box::new(Material::RoughPlastic {
                coating: coating(c(0.5)),
                microfacet: microfacet(Distribution::Beckmann, 0.25, 0.25, true),
            }),
        },
        front.clone(),
    ));
    out.push((
        "blend(0.35, diffuse, roughdielectric)".into(),
        Material::Blend {
            weight: c(0.35),
            first: Box::new(Material::Diffuse { reflectance: c(0.5) }),
            second: Box::new(Material::RoughDielectric {
                interface: interface(1.33),
                microfacet: microfacet(Distribution::Ggx, 0.3, 0.3, true),
            }),
        },
        both.clone(),
    ));
    out.push((
        "twosided(blend(0.5, plastic, roughconductor))".into(),
        Material::TwoSided {
            front: Box::new(Material::Blend {
                weight: c(0.5),
                first: Box::new(Material::Plastic(coating(c(0.4)))),
                second: Box::new(rough.clone()),
            }),
            back: Box::new(Material::Blend {
                weight: c(0.5),
                first: Box::new(Material::Plastic(coating(c(0.4)))),
                second: Box::new(rough),
            }),
        },
        both,
    ));
    out
}

/// Runs the chi-square test (a) and the pdf-integral test (e) on the variants whose name
/// starts with `prefix`.
///
/// The transmission pdf of rough dielectrics is discontinuous along the directions whose half
/// vector is horizontal (facets beyond it do not exist), which the midpoint rule resolves
/// slowly: those variants get 48 x 48 quadrature points per cell, the others 12 x 12.
fn check_sampling(prefix: &str) {
    let mut failures = Vec::new();
    let mut tested = 0;
    for (k, (name, m, wos)) in variants().into_iter().enumerate() {
        if !name.starts_with(prefix) {
            continue;
        }
        let sub = if name.contains("roughdielectric") || name.contains("principled") { 48 } else { 12 };
        let b = build(&m);
        for (j, wo) in wos.into_iter().enumerate() {
            tested += 1;
            let n = 100_000;
            let r = chi2(&b, wo, n, 1000 * k as u64 + j as u64, sub);
            if r.p < SIGNIFICANCE || r.integral > 1.0 + 2e-3 {
                failures
                    .push(format!("{name} wo={wo:.3}: p = {:.2e}, integral of pdf = {:.4}", r.p, r.integral));
            }
            // (e) the pdf integrates to the share of non-delta samples (binomial, 5 sigma +
            // the quadrature's error).
            let share = r.non_delta as f64 / n as f64;
            let sigma = (share * (1.0 - share) / n as f64).sqrt();
            if (r.integral - share).abs() > 5.0 * sigma + 2e-3 {
                failures.push(format!(
                    "{name} wo={wo:.3}: integral of pdf {:.4} vs share {share:.4}",
                    r.integral
                ));
            }
        }
    }
    assert!(tested > 0, "no variant starts with {prefix}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn chi_square_diffuse() {
    check_sampling("diffuse");
}

#[test]
fn chi_square_smooth_conductor_and_dielectrics() {
    // Delta only: checks that no sample claims a density.
    check_sampling("conductor");
    check_sampling("dielectric");
    check_sampling("thindielectric");
}

#[test]
fn chi_square_plastic() {
    check_sampling("plastic");
}

#[test]
fn chi_square_roughconductor() {
    check_sampling("roughconductor");
}

#[test]
fn chi_square_roughdielectric_beckmann() {
    check_sampling("roughdielectric Beckmann");
}

#[test]
fn chi_square_roughdielectric_ggx() {
    check_sampling("roughdielectric Ggx");
}

#[test]
fn chi_square_roughplastic() {
    check_sampling("roughplastic");
}

#[test]
fn chi_square_principled() {
    check_sampling("principled variant principled_");
    check_sampling("principled variant rates");
}

#[test]
fn chi_square_principledthin() {
    check_sampling("principled variant principledthin");
    check_sampling("principled variant thin");
}

#[test]
fn chi_square_wrappers() {
    check_sampling("twosided");
    check_sampling("mask");
    check_sampling("blend");
}

#[test]
fn sample_weights_are_f_cos_over_pdf() {
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    for (name, m, wos) in variants() {
        let b = build(&m);
        for wo in wos {
            for _ in 0..2000 {
                let Some(s) = b.sample(wo, rng.random(), rng.random(), rng.random()) else { continue };
                assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0, "{name}: {s:?}");
                assert!((s.wi.length() - 1.0).abs() < 1e-9, "{name}: {s:?}");
                if s.delta {
                    if !b.has_smooth() {
                        assert_eq!(b.eval(wo, s.wi), DVec3::ZERO, "{name}: a delta BSDF has no density");
                        assert_eq!(b.pdf(wo, s.wi), 0.0, "{name}");
                    }
                    continue;
                }
                let pdf = b.pdf(wo, s.wi);
                let want = b.eval(wo, s.wi) * s.wi.z.abs() / pdf;
                assert!((s.pdf - pdf).abs() <= 1e-9 * pdf, "{name}: pdf {} vs {pdf}", s.pdf);
                assert!(
                    (s.weight - want).abs().max_element() <= 1e-9 * want.max_element().max(1e-9),
                    "{name}: {s:?} vs {want}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------- furnaces

/// The energy a BSDF scatters for `wo`, by Monte Carlo over its own samples: the mean of the
/// weights with refraction's radiance scaling `1 / eta^2` undone (white-furnace albedo).
fn furnace(b: &PhysicalBsdf, wo: DVec3, n: usize, seed: u64) -> DVec3 {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut sum = DVec3::ZERO;
    for _ in 0..n {
        if let Some(s) = b.sample(wo, rng.random(), rng.random(), rng.random()) {
            sum += s.weight * s.eta * s.eta;
        }
    }
    sum / n as f64
}

/// `integral f |cos| dw` over the sphere by quadrature (the non-delta part).
fn furnace_quadrature(b: &PhysicalBsdf, wo: DVec3, res: usize) -> DVec3 {
    let mut sum = DVec3::ZERO;
    let dt = PI / res as f64;
    let dp = TAU / (2 * res) as f64;
    for i in 0..res {
        let theta = (i as f64 + 0.5) * dt;
        let (st, ct) = theta.sin_cos();
        for j in 0..2 * res {
            let phi = (j as f64 + 0.5) * dp;
            let w = DVec3::new(st * phi.cos(), st * phi.sin(), ct);
            sum += b.eval(wo, w) * ct.abs() * st * dt * dp;
        }
    }
    sum
}

fn perfect_metal() -> Metal {
    Metal { eta: DVec3::ONE, k: DVec3::splat(1e6), specular_reflectance: c(1.0) }
}

#[test]
fn furnace_diffuse_is_exactly_one() {
    let b = build(&Material::Diffuse { reflectance: c(1.0) });
    for wo in [dir(0.0, 0.0), dir(45.0, 10.0), dir(89.0, 100.0)] {
        let q = furnace_quadrature(&b, wo, 400);
        assert!((q - DVec3::ONE).abs().max_element() < 1e-4, "{q}");
        let mut rng = Pcg64Mcg::seed_from_u64(5);
        for _ in 0..1000 {
            let s = b.sample(wo, rng.random(), rng.random(), rng.random()).expect("a sample");
            assert_eq!(s.weight, DVec3::ONE);
        }
    }
    // One-sided: black from behind, and towards the back.
    assert!(b.sample(dir(120.0, 0.0), 0.5, 0.5, 0.5).is_none());
    assert_eq!(b.eval(dir(120.0, 0.0), dir(10.0, 0.0)), DVec3::ZERO);
    assert_eq!(b.eval(dir(10.0, 0.0), dir(120.0, 0.0)), DVec3::ZERO);
}

#[test]
fn furnace_smooth_dielectrics_conserve_energy() {
    let eta = 1.5046 / 1.000_277;
    let b = build(&Material::Dielectric(interface(1.5046)));
    let thin = build(&Material::ThinDielectric(interface(1.5046)));
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    for wo in [dir(0.0, 0.0), dir(40.0, 30.0), dir(80.0, 0.0), dir(150.0, 70.0), dir(135.0, 0.0)] {
        let f = fresnel::fresnel_dielectric(wo.z, eta);
        let mut reflected = 0;
        let n = 20_000;
        for _ in 0..n {
            let s = b.sample(wo, rng.random(), rng.random(), rng.random()).expect("a sample");
            assert!(s.delta);
            if s.wi.z * wo.z > 0.0 {
                reflected += 1;
                assert_eq!(s.weight, DVec3::ONE);
                assert_eq!(s.eta, 1.0);
                assert!((s.wi - DVec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-12);
            } else {
                // Radiance scaled by 1 / eta^2; energy R + T = 1 per sample.
                let want = if wo.z > 0.0 { eta } else { 1.0 / eta };
                assert!((s.eta - want).abs() < 1e-12);
                assert!((s.weight * s.eta * s.eta - DVec3::ONE).abs().max_element() < 1e-12);
                // Snell's law.
                let sin_o = (1.0 - wo.z * wo.z).sqrt();
                let sin_i = (1.0 - s.wi.z * s.wi.z).sqrt();
                assert!((sin_o - s.eta * sin_i).abs() < 1e-12);
            }
        }
        let share = reflected as f64 / n as f64;
        let sigma = (f.r * (1.0 - f.r) / n as f64).sqrt().max(1e-9);
        assert!((share - f.r).abs() < 5.0 * sigma + 1e-9, "wo {wo}: reflected {share} vs F {}", f.r);
        // Total internal reflection from inside past the critical angle (41.7 degrees).
        if wo.z < 0.0 && (1.0 - wo.z * wo.z).sqrt() * eta > 1.0 {
            assert_eq!(reflected, n);
        }
        // The thin slab: R' = 2R / (1 + R) below 1, straight transmission, no index change.
        let r = fresnel::fresnel_dielectric(wo.z.abs(), eta).r;
        let mut thin_reflected = 0;
        for _ in 0..n {
            let s = thin.sample(wo, rng.random(), rng.random(), rng.random()).expect("a sample");
            assert_eq!(s.weight, DVec3::ONE);
            assert_eq!(s.eta, 1.0);
            if s.wi.z * wo.z > 0.0 {
                thin_reflected += 1;
            } else {
                assert_eq!(s.wi, -wo);
            }
        }
        let want = 2.0 * r / (1.0 + r);
        let sigma = (want * (1.0 - want) / n as f64).sqrt();
        assert!((thin_reflected as f64 / n as f64 - want).abs() < 5.0 * sigma, "thin wo {wo}");
    }
}

#[test]
fn furnace_conductors() {
    // A perfect conductor (k -> infinity) reflects everything.
    let b = build(&Material::Conductor(perfect_metal()));
    let s = b.sample(dir(30.0, 0.0), 0.5, 0.5, 0.5).expect("a sample");
    assert!((s.weight - DVec3::ONE).abs().max_element() < 1e-5);
    // Gold at normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2) per channel.
    let g = gold();
    let s = build(&Material::Conductor(g.clone())).sample(DVec3::Z, 0.5, 0.5, 0.5).expect("a sample");
    for i in 0..3 {
        let (n, k) = (g.eta[i], g.k[i]);
        let want = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert!((s.weight[i] - want).abs() < 1e-14);
    }
    assert_eq!(s.wi, DVec3::Z);
    // Rough perfect conductors lose the energy of multiple scattering, more as roughness grows.
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        for vis in [true, false] {
            let mut previous = 1.0;
            for alpha in [0.05, 0.3, 0.6, 1.0] {
                let m = Material::RoughConductor {
                    metal: perfect_metal(),
                    microfacet: microfacet(kind, alpha, alpha, vis),
                };
                let b = build(&m);
                let a = furnace(&b, DVec3::Z, 100_000, 3).x;
                let tilted = furnace(&b, dir(70.0, 40.0), 100_000, 4).x;
                assert!(a <= 1.0 + 3e-3 && tilted <= 1.0 + 3e-3, "{kind:?} {alpha}: {a} {tilted}");
                assert!(a <= previous + 3e-3, "{kind:?} {alpha}: {a} after {previous}");
                previous = a;
                if alpha == 0.05 {
                    assert!(a > 0.995, "{kind:?} {alpha}: {a}");
                }
                if alpha == 1.0 {
                    // Single scattering at alpha = 1 (measured: Beckmann keeps 0.459 at normal
                    // incidence and 0.822 at 70 degrees, GGX 0.306 and 0.457; at normal
                    // incidence 37% (Beckmann) and 50% (GGX) of the facets, those steeper than
                    // 45 degrees, reflect below the horizon).
                    let (lo_n, lo_t) =
                        if kind == Distribution::Beckmann { (0.42, 0.78) } else { (0.28, 0.42) };
                    assert!(a > lo_n && tilted > lo_t, "{kind:?} {alpha}: {a} {tilted}");
                }
            }
        }
    }
}

#[test]
fn furnace_rough_dielectric_loses_only_to_single_scattering() {
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        for alpha in [0.02, 0.3, 1.0] {
            let m = Material::RoughDielectric {
                interface: interface(1.5046),
                microfacet: microfacet(kind, alpha, alpha, true),
            };
            let b = build(&m);
            for wo in [dir(0.0, 0.0), dir(60.0, 20.0), dir(170.0, 0.0), dir(120.0, 50.0)] {
                let a = furnace(&b, wo, 100_000, 9).x;
                assert!(a <= 1.0 + 3e-3, "{kind:?} {alpha} {wo}: {a}");
                // Measured minima over these directions: 0.9989 (alpha 0.02), 0.781 (GGX 0.3
                // from inside at 60 degrees), 0.420 (GGX 1 from inside near the normal).
                let bound = if alpha < 0.1 {
                    0.99
                } else if alpha < 0.5 {
                    0.75
                } else {
                    0.4
                };
                assert!(a > bound, "{kind:?} {alpha} {wo}: {a}");
            }
        }
    }
}

#[test]
fn furnace_plastics() {
    // Smooth plastic with a white base: F + (1 - F) (1 - Fdr_ext) / (eta^2 (1 - Fdr_int)),
    // which is 1 but for the error of the Fdr fits.
    let b = build(&Material::Plastic(coating(c(1.0))));
    for wo in [dir(0.0, 0.0), dir(60.0, 0.0), dir(85.0, 0.0)] {
        let a = furnace(&b, wo, 200_000, 2).x;
        assert!((a - 1.0).abs() < 0.01, "{wo}: {a}");
    }
    let b = build(&Material::Plastic(coating(c(0.0))));
    let a = furnace(&b, dir(60.0, 0.0), 10_000, 2).x;
    let f = fresnel::fresnel_dielectric(0.5, 1.49 / 1.000_277).r;
    assert!((a - f).abs() < 1e-12, "a black base reflects F only: {a} vs {f}");
    // Rough plastic: at most 1, at least what single scattering keeps.
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        for alpha in [0.05, 0.3, 0.8] {
            let m = Material::RoughPlastic {
                coating: coating(c(1.0)),
                microfacet: microfacet(kind, alpha, alpha, true),
            };
            let b = build(&m);
            for wo in [dir(0.0, 0.0), dir(70.0, 0.0)] {
                let a = furnace(&b, wo, 100_000, 6).x;
                // Measured: 0.977 / 0.874 / 0.585 (Beckmann 0.05 / 0.3 / 0.8 at normal
                // incidence), 0.957 / 0.694 / 0.404 (GGX); at 70 degrees down to 0.305.
                let bound = if alpha < 0.1 {
                    0.95
                } else if alpha < 0.5 {
                    0.6
                } else {
                    0.28
                };
                assert!(a <= 1.01 && a > bound, "{kind:?} {alpha} {wo}: {a}");
            }
        }
    }
}

#[test]
fn furnace_principled() {
    let principled = |m: Principled| build(&Material::Principled(Principled { base_color: c(1.0), ..m }));
    let thin =
        |m: PrincipledThin| build(&Material::PrincipledThin(PrincipledThin { base_color: c(1.0), ..m }));
    let d = principled_defaults();
    let t = thin_defaults();
    let wos = [dir(0.0, 0.0), dir(45.0, 0.0), dir(70.0, 0.0), dir(85.0, 0.0), dir(150.0, 0.0)];
    // The single-scattering microfacet lobes conserve (white metal, white glass with the
    // radiance scaling undone, the thin sheet's specular lobes).
    for (name, b) in [
        ("metal 0.2", principled(Principled { metallic: c(1.0), roughness: c(0.2), ..d.clone() })),
        ("metal 0.9", principled(Principled { metallic: c(1.0), roughness: c(0.9), ..d.clone() })),
        ("glass", principled(Principled { spec_trans: c(1.0), roughness: c(0.3), eta: 1.5, ..d.clone() })),
        ("thin specular", thin(PrincipledThin { spec_trans: c(1.0), ..t.clone() })),
    ] {
        for wo in wos {
            let a = furnace(&b, wo, 100_000, 3).x;
            assert!(a <= 1.0 + 5e-3, "{name} {wo}: {a}");
        }
    }
    // Mitsuba's Disney diffuse (retro-reflection), sheen and clearcoat add energy: a white
    // `principled` reflects more than it receives, most at grazing angles (as Mitsuba's own
    // samples show: 1.0437 at normal incidence and 1.1137 at 70 degrees for the defaults, 1.0733
    // and 1.1253 with a full glossy clearcoat; 40,000 samples each, `scalar_rgb`).
    for (name, b, want) in [
        ("defaults", principled(d.clone()), [1.0437, 1.1137]),
        (
            "clearcoat",
            principled(Principled { clearcoat: c(1.0), clearcoat_gloss: c(1.0), ..d.clone() }),
            [1.0733, 1.1253],
        ),
    ] {
        for (wo, want) in [dir(0.0, 0.0), dir(70.0, 0.0)].into_iter().zip(want) {
            let a = furnace(&b, wo, 200_000, 4).x;
            assert!((a - want).abs() < 0.01, "{name} {wo}: {a} vs Mitsuba's {want}");
        }
        assert!(furnace(&b, dir(85.0, 0.0), 100_000, 5).x > 1.1, "{name}");
    }
    let b = thin(t);
    assert!(furnace(&b, dir(85.0, 0.0), 100_000, 5).x > 1.01, "the thin sheet's diffuse, too");
}

// ---------------------------------------------------------------- reciprocity and exact values

#[test]
fn reflection_is_reciprocal_and_transmission_generalised_reciprocal() {
    let mut rng = Pcg64Mcg::seed_from_u64(21);
    let eta = 1.5046 / 1.000_277;
    for (name, m, _) in variants() {
        let b = build(&m);
        for _ in 0..500 {
            let a = sphere(&mut rng);
            let d = sphere(&mut rng);
            let (fab, fba) = (b.eval(a, d), b.eval(d, a));
            if a.z * d.z > 0.0 || name.contains("blend") {
                // Reflection (and the blend, whose dielectric has index 1.33: skipped below).
                if a.z * d.z > 0.0 {
                    assert!(
                        (fab - fba).abs().max_element() <= 1e-9 * fab.max_element().max(1e-12),
                        "{name}: {fab} {fba}"
                    );
                }
            } else if name.contains("principledthin") || name.contains("thin rates") {
                // Not reciprocal in transmission, as Mitsuba's: the specular transmission's
                // masking tests the direction below against the half vector of the mirrored
                // one (`wi . h < 0`), a condition that is not symmetric in the two directions.
            } else if name.contains("principled_glass") {
                // As the rough dielectric's, with the index 1.4.
                let n = |w: DVec3| if w.z > 0.0 { 1.0 } else { 1.4 };
                let (l, r) = (fab / (n(a) * n(a)), fba / (n(d) * n(d)));
                assert!((l - r).abs().max_element() <= 1e-9 * l.max_element().max(1e-12), "{name}: {l} {r}");
            } else if name.starts_with("roughdielectric") {
                // f(a, d) / n_a^2 = f(d, a) / n_d^2, n the index of each direction's side.
                let n = |w: DVec3| if w.z > 0.0 { 1.0 } else { eta };
                let (l, r) = (fab / (n(a) * n(a)), fba / (n(d) * n(d)));
                assert!((l - r).abs().max_element() <= 1e-9 * l.max_element().max(1e-12), "{name}: {l} {r}");
            }
        }
    }
}

fn sphere(rng: &mut Pcg64Mcg) -> DVec3 {
    crate::base::sampling::uniform_sphere(rng.random(), rng.random())
}

#[test]
fn rough_conductor_matches_the_cook_torrance_formula() {
    // At wo = wi = +z: h = z, G = 1, F = F(1), D(z) = 1 / (pi au av) for both kinds.
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        let m = Material::RoughConductor { metal: gold(), microfacet: microfacet(kind, 0.2, 0.4, true) };
        let f = build(&m).eval(DVec3::Z, DVec3::Z);
        let g = gold();
        let want = fresnel::fresnel_conductor(1.0, g.eta, g.k) / (PI * 0.2 * 0.4) / 4.0;
        assert!((f - want).abs().max_element() < 1e-12, "{kind:?}: {f} vs {want}");
    }
    // Anisotropy: a lobe stretched along x (alpha_u > alpha_v) reflects more off the mirror
    // direction along x than along y.
    let m =
        Material::RoughConductor { metal: gold(), microfacet: microfacet(Distribution::Ggx, 0.5, 0.1, true) };
    let b = build(&m);
    let wo = DVec3::Z;
    assert!(b.eval(wo, dir(20.0, 0.0)).x > 10.0 * b.eval(wo, dir(20.0, 90.0)).x);
}

#[test]
fn rough_plastic_tables_approach_the_smooth_limits() {
    use roughplastic::CoatingTable;
    let eta = 1.49 / 1.000_277;
    let t = CoatingTable::compute(Distribution::Ggx, 0.01, eta);
    for mu in [1.0, 0.7, 0.3] {
        let smooth = 1.0 - fresnel::fresnel_dielectric(mu, eta).r;
        assert!((t.transmittance(mu) - smooth).abs() < 2e-3, "T({mu}) = {} vs {smooth}", t.transmittance(mu));
    }
    let fdr = fresnel::fresnel_diffuse_reflectance(1.0 / eta);
    assert!((t.internal_reflectance - fdr).abs() < 0.02, "{} vs {fdr}", t.internal_reflectance);
    // Rougher coatings transmit less at grazing angles than smooth ones transmit... and more
    // at normal incidence than they reflect.
    let rough = CoatingTable::compute(Distribution::Beckmann, 0.5, eta);
    assert!(rough.transmittance(1.0) > 0.9 && rough.transmittance(1.0) < 1.0);
    assert!(rough.external_transmittance.iter().all(|&x| (0.0..=1.0).contains(&x)));
}

// ---------------------------------------------------------------- wrappers

#[test]
fn twosided_shows_the_back_material_flipped() {
    let front = Material::Diffuse { reflectance: c(0.2) };
    let back =
        Material::RoughConductor { metal: gold(), microfacet: microfacet(Distribution::Ggx, 0.3, 0.3, true) };
    let b = build(&Material::TwoSided { front: Box::new(front.clone()), back: Box::new(back.clone()) });
    let (fb, bb) = (build(&front), build(&back));
    let flip = |w: DVec3| DVec3::new(w.x, w.y, -w.z);
    let (wo, wi) = (dir(30.0, 10.0), dir(50.0, 200.0));
    assert_eq!(b.eval(wo, wi), fb.eval(wo, wi));
    assert_eq!(b.eval(flip(wo), flip(wi)), bb.eval(wo, wi));
    assert_eq!(b.pdf(flip(wo), flip(wi)), bb.pdf(wo, wi));
    // Across the surface: black (both nested BSDFs are one-sided).
    assert_eq!(b.eval(wo, flip(wi)), DVec3::ZERO);
    let s = b.sample(flip(wo), 0.3, 0.4, 0.6).expect("a sample");
    let t = bb.sample(wo, 0.3, 0.4, 0.6).expect("a sample");
    assert_eq!(s.wi, flip(t.wi));
    assert_eq!(s.weight, t.weight);
    assert!(b.has_smooth());
    assert_eq!(b.albedo(), DVec3::splat(0.2));
}

#[test]
fn mask_passes_light_with_probability_one_minus_opacity() {
    let inner = Material::Diffuse { reflectance: c(0.8) };
    let b = build(&Material::Mask { opacity: c(0.3), material: Box::new(inner.clone()) });
    let ib = build(&inner);
    let (wo, wi) = (dir(30.0, 10.0), dir(50.0, 200.0));
    assert!((b.eval(wo, wi) - 0.3 * ib.eval(wo, wi)).abs().max_element() < 1e-15);
    assert!((b.pdf(wo, wi) - 0.3 * ib.pdf(wo, wi)).abs() < 1e-15);
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let n = 100_000;
    let mut null = 0;
    let mut sum = DVec3::ZERO;
    for _ in 0..n {
        let s = b.sample(wo, rng.random(), rng.random(), rng.random()).expect("a sample");
        if s.delta {
            null += 1;
            assert_eq!(s.wi, -wo);
            assert_eq!(s.weight, DVec3::ONE);
            assert!((s.pdf - 0.7).abs() < 1e-15);
        } else {
            // The mixture's own weight: 0.3 f cos / (0.3 pdf) = 0.8.
            assert!((s.weight - DVec3::splat(0.8)).abs().max_element() < 1e-12);
            sum += s.weight;
        }
    }
    let share = null as f64 / n as f64;
    assert!((share - 0.7).abs() < 5.0 * (0.21 / n as f64).sqrt());
    // Expected reflected energy 0.3 * 0.8.
    assert!((sum.x / n as f64 - 0.24).abs() < 0.005);
    // Works from behind too (the pass-through is two-sided).
    let s = b.sample(dir(120.0, 0.0), 0.9, 0.5, 0.5).expect("a pass-through");
    assert!(s.delta && s.wi == -dir(120.0, 0.0));
    assert!(b.sample(dir(120.0, 0.0), 0.1, 0.5, 0.5).is_none());
}

#[test]
fn blend_mixes_eval_and_pdf_and_samples_by_weight() {
    let a = Material::Diffuse { reflectance: c(0.5) };
    let d = Material::Dielectric(interface(1.5));
    let b = build(&Material::Blend { weight: c(0.25), first: Box::new(a.clone()), second: Box::new(d) });
    let ab = build(&a);
    let (wo, wi) = (dir(30.0, 10.0), dir(50.0, 200.0));
    assert!((b.eval(wo, wi) - 0.75 * ab.eval(wo, wi)).abs().max_element() < 1e-15);
    assert!((b.pdf(wo, wi) - 0.75 * ab.pdf(wo, wi)).abs() < 1e-15);
    let mut rng = Pcg64Mcg::seed_from_u64(2);
    let n = 100_000;
    let mut delta = 0;
    for _ in 0..n {
        if let Some(s) = b.sample(wo, rng.random(), rng.random(), rng.random())
            && s.delta
        {
            delta += 1;
            // The dielectric's own weight (its choice probability cancels its weight).
            assert!(
                s.weight == DVec3::ONE || (s.weight * s.eta * s.eta - DVec3::ONE).abs().max_element() < 1e-12
            );
        }
    }
    assert!((delta as f64 / n as f64 - 0.25).abs() < 5.0 * (0.1875 / n as f64).sqrt());
    assert!(b.has_smooth());
    assert!(!build(&Material::Dielectric(interface(1.5))).has_smooth());
}

#[test]
fn nested_wrappers_flatten_within_capacity() {
    let leaf = || Box::new(Material::Diffuse { reflectance: c(0.5) });
    let blend = |a, b| Box::new(Material::Blend { weight: c(0.5), first: a, second: b });
    let four = blend(blend(leaf(), leaf()), blend(leaf(), leaf()));
    let m = Material::TwoSided { front: four.clone(), back: four };
    assert_eq!(component_count(&m), 8);
    let b = build(&m);
    assert_eq!(b.components().len(), 8);
    assert_eq!(b.components().iter().filter(|c| c.side == Side::Back && c.flip).count(), 4);
    // Weight 0 drops a branch; a course material has no physically based lobes.
    let b = build(&Material::Blend { weight: c(0.0), first: leaf(), second: leaf() });
    assert_eq!(b.components().len(), 1);
    let b = build(&Material::Course(crate::material::CourseMaterial::default()));
    assert!(b.components().is_empty() && b.sample(DVec3::Z, 0.5, 0.5, 0.5).is_none());
    // Twosided inside twosided: the inner back branch is unreachable from the outer front.
    let inner = Material::TwoSided { front: leaf(), back: leaf() };
    let b = build(&Material::TwoSided { front: Box::new(inner.clone()), back: Box::new(inner) });
    assert_eq!(b.components().len(), 2);
}

// ---------------------------------------------------------------- against Mitsuba 3

/// A reference value: material name, `wo` and `wi` as (theta, phi) in degrees, `f`, `pdf`.
type Reference = (&'static str, (f64, f64), (f64, f64), [f64; 3], f64);

/// `f` (Mitsuba's `eval` divided by `|cos wi|`) and `pdf` computed by Mitsuba 3.9.1
/// (`scalar_rgb`, single precision) for the materials of [`mitsuba_material`], at directions
/// given as (theta, phi) in degrees: `(name, wo, wi, f, pdf)`. Printed by
/// `tools/mitsuba/bsdf_reference.py` (each plugin loaded with `mi.load_dict`, `eval` and `pdf`
/// called with `si.wi = wo`).
const MITSUBA_REFERENCE: &[Reference] = &[
    (
        "roughconductor_ggx",
        (30.0, 20.0),
        (50.0, 200.0),
        [6.1378208e-01, 5.0922385e-01, 2.1039072e-01],
        4.1619128e-01,
    ),
    (
        "roughconductor_ggx",
        (0.0, 0.0),
        (20.0, 10.0),
        [3.5081500e-01, 2.9112442e-01, 1.1761078e-01],
        3.4152010e-01,
    ),
    (
        "roughconductor_ggx",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughconductor_ggx",
        (70.0, 0.0),
        (60.0, 180.0),
        [3.6284900e+00, 3.0595829e+00, 1.4973890e+00],
        1.9435487e+00,
    ),
    (
        "roughconductor_ggx",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughconductor_ggx",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughconductor_beckmann",
        (30.0, 20.0),
        (50.0, 200.0),
        [1.1545288e+00, 9.5785398e-01, 3.9574654e-01],
        7.6838833e-01,
    ),
    (
        "roughconductor_beckmann",
        (0.0, 0.0),
        (20.0, 10.0),
        [6.8454090e-01, 5.6806743e-01, 2.2949243e-01],
        6.6544402e-01,
    ),
    (
        "roughconductor_beckmann",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughconductor_beckmann",
        (70.0, 0.0),
        (60.0, 180.0),
        [4.5982709e+00, 3.8773129e+00, 1.8975939e+00],
        2.3932345e+00,
    ),
    (
        "roughconductor_beckmann",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughconductor_beckmann",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughdielectric_ggx",
        (30.0, 20.0),
        (50.0, 200.0),
        [4.1581738e-02, 4.1581738e-02, 4.1581738e-02],
        2.7556675e-02,
    ),
    (
        "roughdielectric_ggx",
        (0.0, 0.0),
        (20.0, 10.0),
        [2.2342863e-02, 2.2342863e-02, 2.2342863e-02],
        2.1057818e-02,
    ),
    (
        "roughdielectric_ggx",
        (60.0, 120.0),
        (140.0, 300.0),
        [6.4646429e+00, 6.4646429e+00, 6.4646429e+00],
        1.1379472e+01,
    ),
    (
        "roughdielectric_ggx",
        (70.0, 0.0),
        (60.0, 180.0),
        [4.4289228e-01, 4.4289228e-01, 4.4289228e-01],
        2.3550162e-01,
    ),
    (
        "roughdielectric_ggx",
        (150.0, 40.0),
        (30.0, 250.0),
        [6.0152984e-01, 6.0152984e-01, 6.0152984e-01],
        2.3195699e-01,
    ),
    (
        "roughdielectric_ggx",
        (150.0, 40.0),
        (120.0, 220.0),
        [6.7743921e-01, 6.7743921e-01, 6.7743921e-01],
        3.6021861e-01,
    ),
    (
        "roughdielectric_beckmann",
        (30.0, 20.0),
        (50.0, 200.0),
        [2.4854914e-02, 2.4854914e-02, 2.4854914e-02],
        1.5976429e-02,
    ),
    (
        "roughdielectric_beckmann",
        (0.0, 0.0),
        (20.0, 10.0),
        [1.2896126e-02, 1.2896126e-02, 1.2896126e-02],
        1.2118395e-02,
    ),
    (
        "roughdielectric_beckmann",
        (60.0, 120.0),
        (140.0, 300.0),
        [3.6205007e+00, 3.6205007e+00, 3.6205007e+00],
        6.2751484e+00,
    ),
    (
        "roughdielectric_beckmann",
        (70.0, 0.0),
        (60.0, 180.0),
        [2.0387998e-01, 2.0387998e-01, 2.0387998e-01],
        1.0302260e-01,
    ),
    (
        "roughdielectric_beckmann",
        (150.0, 40.0),
        (30.0, 250.0),
        [7.8247515e-01, 7.8247515e-01, 7.8247515e-01],
        2.9950199e-01,
    ),
    (
        "roughdielectric_beckmann",
        (150.0, 40.0),
        (120.0, 220.0),
        [6.2699324e-01, 6.2699324e-01, 6.2699324e-01],
        3.1682593e-01,
    ),
    ("plastic", (30.0, 20.0), (50.0, 200.0), [1.9041175e-01, 9.5205877e-02, 3.1735292e-02], 1.8178070e-01),
    ("plastic", (0.0, 0.0), (20.0, 10.0), [1.9418571e-01, 9.7092856e-02, 3.2364283e-02], 2.6690218e-01),
    ("plastic", (60.0, 120.0), (140.0, 300.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("plastic", (70.0, 0.0), (60.0, 180.0), [1.5937147e-01, 7.9685733e-02, 2.6561910e-02], 9.8827399e-02),
    ("plastic", (150.0, 40.0), (30.0, 250.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("plastic", (150.0, 40.0), (120.0, 220.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("plastic_nl", (30.0, 20.0), (50.0, 200.0), [2.4962478e-01, 2.4962478e-01, 2.4962478e-01], 1.9551332e-01),
    ("plastic_nl", (0.0, 0.0), (20.0, 10.0), [2.5457235e-01, 2.5457235e-01, 2.5457235e-01], 2.8631562e-01),
    (
        "plastic_nl",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    ("plastic_nl", (70.0, 0.0), (60.0, 180.0), [2.0893179e-01, 2.0893179e-01, 2.0893179e-01], 1.2980728e-01),
    (
        "plastic_nl",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "plastic_nl",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughplastic_ggx",
        (30.0, 20.0),
        (50.0, 200.0),
        [1.4537195e-01, 1.8759536e-01, 8.2036855e-02],
        2.4667512e-01,
    ),
    (
        "roughplastic_ggx",
        (0.0, 0.0),
        (20.0, 10.0),
        [1.3152966e-01, 1.7561516e-01, 6.5401408e-02],
        3.1950107e-01,
    ),
    (
        "roughplastic_ggx",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughplastic_ggx",
        (70.0, 0.0),
        (60.0, 180.0),
        [5.2344906e-01, 5.5947465e-01, 4.6941072e-01],
        6.8649095e-01,
    ),
    (
        "roughplastic_ggx",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughplastic_ggx",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughplastic_beckmann",
        (30.0, 20.0),
        (50.0, 200.0),
        [1.2112622e-01, 1.8205638e-01, 5.9401814e-02],
        2.2377373e-01,
    ),
    (
        "roughplastic_beckmann",
        (0.0, 0.0),
        (20.0, 10.0),
        [1.0852680e-01, 1.7074675e-01, 4.5495789e-02],
        3.0534813e-01,
    ),
    (
        "roughplastic_beckmann",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughplastic_beckmann",
        (70.0, 0.0),
        (60.0, 180.0),
        [2.6837437e+00, 2.7346880e+00, 2.6321354e+00],
        3.4543254e+00,
    ),
    (
        "roughplastic_beckmann",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "roughplastic_beckmann",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    ("diffuse", (30.0, 20.0), (50.0, 200.0), [2.5464793e-01, 1.5915495e-01, 6.3661982e-02], 2.0460565e-01),
    ("diffuse", (0.0, 0.0), (20.0, 10.0), [2.5464791e-01, 1.5915494e-01, 6.3661977e-02], 2.9911345e-01),
    ("diffuse", (60.0, 120.0), (140.0, 300.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("diffuse", (70.0, 0.0), (60.0, 180.0), [2.5464791e-01, 1.5915494e-01, 6.3661978e-02], 1.5915494e-01),
    ("diffuse", (150.0, 40.0), (30.0, 250.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("diffuse", (150.0, 40.0), (120.0, 220.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("twosided", (30.0, 20.0), (50.0, 200.0), [2.5464793e-01, 1.5915495e-01, 6.3661982e-02], 2.0460565e-01),
    ("twosided", (0.0, 0.0), (20.0, 10.0), [2.5464791e-01, 1.5915494e-01, 6.3661977e-02], 2.9911345e-01),
    ("twosided", (60.0, 120.0), (140.0, 300.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("twosided", (70.0, 0.0), (60.0, 180.0), [2.5464791e-01, 1.5915494e-01, 6.3661978e-02], 1.5915494e-01),
    ("twosided", (150.0, 40.0), (30.0, 250.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("twosided", (150.0, 40.0), (120.0, 220.0), [4.7452998e-01, 3.9381355e-01, 1.6511269e-01], 2.6133287e-01),
    ("mask", (30.0, 20.0), (50.0, 200.0), [4.3611588e-02, 5.6278613e-02, 2.4611059e-02], 7.4002542e-02),
    ("mask", (0.0, 0.0), (20.0, 10.0), [3.9458900e-02, 5.2684550e-02, 1.9620424e-02], 9.5850326e-02),
    ("mask", (60.0, 120.0), (140.0, 300.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("mask", (70.0, 0.0), (60.0, 180.0), [1.5703472e-01, 1.6784240e-01, 1.4082322e-01], 2.0594729e-01),
    ("mask", (150.0, 40.0), (30.0, 250.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("mask", (150.0, 40.0), (120.0, 220.0), [0.0000000e+00, 0.0000000e+00, 0.0000000e+00], 0.0000000e+00),
    ("blend", (30.0, 20.0), (50.0, 200.0), [1.9072807e-01, 1.2388299e-01, 5.7037908e-02], 1.5149096e-01),
    ("blend", (0.0, 0.0), (20.0, 10.0), [1.8495639e-01, 1.1811132e-01, 5.1266241e-02], 2.1569675e-01),
    ("blend", (60.0, 120.0), (140.0, 300.0), [1.9393929e+00, 1.9393929e+00, 1.9393929e+00], 3.4138417e+00),
    ("blend", (70.0, 0.0), (60.0, 180.0), [3.1112123e-01, 2.4427615e-01, 1.7743108e-01], 1.8205895e-01),
    ("blend", (150.0, 40.0), (30.0, 250.0), [1.8045895e-01, 1.8045895e-01, 1.8045895e-01], 6.9587097e-02),
    ("blend", (150.0, 40.0), (120.0, 220.0), [2.0323177e-01, 2.0323177e-01, 2.0323177e-01], 1.0806559e-01),
    (
        "principled_default",
        (30.0, 20.0),
        (50.0, 200.0),
        [2.0752574e-01, 2.0752574e-01, 2.0752574e-01],
        4.4903091e-01,
    ),
    (
        "principled_default",
        (0.0, 0.0),
        (20.0, 10.0),
        [1.8480814e-01, 1.8480814e-01, 1.8480814e-01],
        4.5138812e-01,
    ),
    (
        "principled_default",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principled_default",
        (70.0, 0.0),
        (60.0, 180.0),
        [7.7670473e-01, 7.7670473e-01, 7.7670473e-01],
        1.4351349e+00,
    ),
    (
        "principled_default",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principled_default",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        3.6390570e-01,
    ),
    (
        "principled_full",
        (30.0, 20.0),
        (50.0, 200.0),
        [5.7601873e-01, 2.4232850e-01, 1.0885239e-01],
        6.0260522e-01,
    ),
    (
        "principled_full",
        (0.0, 0.0),
        (20.0, 10.0),
        [4.6415799e-01, 1.9363998e-01, 8.5432745e-02],
        6.7969924e-01,
    ),
    (
        "principled_full",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principled_full",
        (70.0, 0.0),
        (60.0, 180.0),
        [8.6081371e+00, 4.6762066e+00, 3.1034338e+00],
        6.9344177e+00,
    ),
    (
        "principled_full",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principled_full",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        1.1765905e-01,
    ),
    (
        "principled_glass",
        (30.0, 20.0),
        (50.0, 200.0),
        [1.9481386e-01, 1.7712144e-01, 1.5942899e-01],
        2.3093440e-01,
    ),
    (
        "principled_glass",
        (0.0, 0.0),
        (20.0, 10.0),
        [1.3397630e-01, 1.2108135e-01, 1.0818640e-01],
        2.1696226e-01,
    ),
    (
        "principled_glass",
        (60.0, 120.0),
        (140.0, 300.0),
        [2.1341209e+01, 2.0120683e+01, 1.8821176e+01],
        2.8752110e+01,
    ),
    (
        "principled_glass",
        (70.0, 0.0),
        (60.0, 180.0),
        [1.9452170e+00, 1.8437679e+00, 1.7423186e+00],
        1.5884897e+00,
    ),
    (
        "principled_glass",
        (150.0, 40.0),
        (30.0, 250.0),
        [1.1398582e-01, 1.0746686e-01, 1.0052604e-01],
        7.3891625e-02,
    ),
    (
        "principled_glass",
        (150.0, 40.0),
        (120.0, 220.0),
        [1.7655520e-01, 1.7655520e-01, 1.7655520e-01],
        1.2491831e-01,
    ),
    (
        "principled_metal",
        (30.0, 20.0),
        (50.0, 200.0),
        [3.0849638e-01, 2.0574433e-01, 6.8741601e-02],
        2.2047551e-01,
    ),
    (
        "principled_metal",
        (0.0, 0.0),
        (20.0, 10.0),
        [2.0914852e-01, 1.3943236e-01, 4.6477447e-02],
        2.1838820e-01,
    ),
    (
        "principled_metal",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principled_metal",
        (70.0, 0.0),
        (60.0, 180.0),
        [1.3187796e+01, 9.1030645e+00, 3.6567526e+00],
        7.2866259e+00,
    ),
    (
        "principled_metal",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principled_metal",
        (150.0, 40.0),
        (120.0, 220.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        3.1694088e-02,
    ),
    (
        "principledthin_default",
        (30.0, 20.0),
        (50.0, 200.0),
        [1.5923592e-01, 1.5923592e-01, 1.5923592e-01],
        2.0460565e-01,
    ),
    (
        "principledthin_default",
        (0.0, 0.0),
        (20.0, 10.0),
        [1.5915501e-01, 1.5915501e-01, 1.5915501e-01],
        2.9911345e-01,
    ),
    (
        "principledthin_default",
        (60.0, 120.0),
        (140.0, 300.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principledthin_default",
        (70.0, 0.0),
        (60.0, 180.0),
        [1.5131140e-01, 1.5131140e-01, 1.5131140e-01],
        1.5915494e-01,
    ),
    (
        "principledthin_default",
        (150.0, 40.0),
        (30.0, 250.0),
        [0.0000000e+00, 0.0000000e+00, 0.0000000e+00],
        0.0000000e+00,
    ),
    (
        "principledthin_default",
        (150.0, 40.0),
        (120.0, 220.0),
        [1.5915494e-01, 1.5915494e-01, 1.5915494e-01],
        1.5915494e-01,
    ),
    (
        "principledthin_full",
        (30.0, 20.0),
        (50.0, 200.0),
        [8.2431240e-02, 2.7260259e-02, 2.7260259e-02],
        3.2408237e-01,
    ),
    (
        "principledthin_full",
        (0.0, 0.0),
        (20.0, 10.0),
        [7.0952079e-02, 1.9859337e-02, 1.9859337e-02],
        3.7896883e-01,
    ),
    (
        "principledthin_full",
        (60.0, 120.0),
        (140.0, 300.0),
        [4.9538210e-02, 7.0768872e-03, 7.0768872e-03],
        4.2166617e-02,
    ),
    (
        "principledthin_full",
        (70.0, 0.0),
        (60.0, 180.0),
        [1.3981906e+00, 1.2570949e+00, 1.2570949e+00],
        3.7332039e+00,
    ),
    (
        "principledthin_full",
        (150.0, 40.0),
        (30.0, 250.0),
        [7.9415844e-02, 1.1345122e-02, 1.1345122e-02],
        6.6363953e-02,
    ),
    (
        "principledthin_full",
        (150.0, 40.0),
        (120.0, 220.0),
        [6.5358974e-02, 1.2466600e-02, 1.2466600e-02],
        7.9861097e-02,
    ),
    (
        "principledthin_clear",
        (30.0, 20.0),
        (50.0, 200.0),
        [6.5190829e-02, 6.5190829e-02, 6.5190829e-02],
        3.6988327e-01,
    ),
    (
        "principledthin_clear",
        (0.0, 0.0),
        (20.0, 10.0),
        [4.1720867e-02, 4.1720867e-02, 4.1720867e-02],
        3.3316463e-01,
    ),
    (
        "principledthin_clear",
        (60.0, 120.0),
        (140.0, 300.0),
        [2.9764681e-01, 2.9764681e-01, 2.9764681e-01],
        2.4212922e-01,
    ),
    (
        "principledthin_clear",
        (70.0, 0.0),
        (60.0, 180.0),
        [1.1280560e+00, 1.1280560e+00, 1.1280560e+00],
        2.3683264e+00,
    ),
    (
        "principledthin_clear",
        (150.0, 40.0),
        (30.0, 250.0),
        [2.7134100e-01, 2.7134100e-01, 2.7134100e-01],
        2.4518761e-01,
    ),
    (
        "principledthin_clear",
        (150.0, 40.0),
        (120.0, 220.0),
        [4.1096158e-02, 4.1096158e-02, 4.1096158e-02],
        1.4383136e-01,
    ),
];

/// Mitsuba's `principled` index for a `specular` value.
fn eta_of_specular(specular: f64) -> f64 {
    2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
}

/// `principled` with Mitsuba's defaults.
fn principled_defaults() -> Principled {
    Principled {
        base_color: c(0.5),
        roughness: c(0.5),
        anisotropic: c(0.0),
        metallic: c(0.0),
        spec_trans: c(0.0),
        spec_tint: c(0.0),
        sheen: c(0.0),
        sheen_tint: c(0.0),
        flatness: c(0.0),
        clearcoat: c(0.0),
        clearcoat_gloss: c(0.0),
        eta: eta_of_specular(0.5),
        specular_sampling_rate: 1.0,
        clearcoat_sampling_rate: 1.0,
        diffuse_sampling_rate: 1.0,
    }
}

/// `principledthin` with Mitsuba's defaults.
fn thin_defaults() -> PrincipledThin {
    PrincipledThin {
        base_color: c(0.5),
        roughness: c(0.5),
        anisotropic: c(0.0),
        spec_trans: c(0.0),
        eta: c(1.5),
        spec_tint: c(0.0),
        sheen: c(0.0),
        sheen_tint: c(0.0),
        flatness: c(0.0),
        diff_trans: c(0.0),
        specular_reflectance_sampling_rate: 1.0,
        specular_transmittance_sampling_rate: 1.0,
        diffuse_reflectance_sampling_rate: 1.0,
        diffuse_transmittance_sampling_rate: 1.0,
    }
}

/// The materials of [`MITSUBA_REFERENCE`], with Mitsuba's defaults (`bk7` in air for the
/// dielectrics, polypropylene in air for the plastics, visible-normal sampling).
fn mitsuba_material(name: &str) -> Material {
    let metal = Metal {
        eta: DVec3::new(0.143_119, 0.374_957, 1.442_479),
        k: DVec3::new(3.983_160, 2.385_721, 1.603_215),
        specular_reflectance: c(1.0),
    };
    let base = rgb(0.5, 0.7, 0.2);
    match name {
        "roughconductor_ggx" => {
            Material::RoughConductor { metal, microfacet: microfacet(Distribution::Ggx, 0.2, 0.4, true) }
        }
        "roughconductor_beckmann" => {
            Material::RoughConductor { metal, microfacet: microfacet(Distribution::Beckmann, 0.3, 0.3, true) }
        }
        "roughdielectric_ggx" => Material::RoughDielectric {
            interface: interface(1.5046),
            microfacet: microfacet(Distribution::Ggx, 0.3, 0.3, true),
        },
        "roughdielectric_beckmann" => Material::RoughDielectric {
            interface: interface(1.5046),
            microfacet: microfacet(Distribution::Beckmann, 0.5, 0.5, true),
        },
        "plastic" => Material::Plastic(coating(rgb(0.6, 0.3, 0.1))),
        "plastic_nl" => Material::Plastic(Coating { nonlinear: true, ..coating(c(0.9)) }),
        "roughplastic_ggx" => Material::RoughPlastic {
            coating: coating(base),
            microfacet: microfacet(Distribution::Ggx, 0.3, 0.3, true),
        },
        "roughplastic_beckmann" => Material::RoughPlastic {
            coating: Coating { nonlinear: true, ..coating(base) },
            microfacet: microfacet(Distribution::Beckmann, 0.1, 0.1, true),
        },
        "diffuse" => Material::Diffuse { reflectance: rgb(0.8, 0.5, 0.2) },
        "twosided" => Material::TwoSided {
            front: Box::new(mitsuba_material("diffuse")),
            back: Box::new(mitsuba_material("roughconductor_ggx")),
        },
        "mask" => {
            Material::Mask { opacity: c(0.3), material: Box::new(mitsuba_material("roughplastic_ggx")) }
        }
        "blend" => Material::Blend {
            weight: c(0.3),
            first: Box::new(mitsuba_material("diffuse")),
            second: Box::new(mitsuba_material("roughdielectric_ggx")),
        },
        "principled_default" => Material::Principled(principled_defaults()),
        "principled_full" => Material::Principled(Principled {
            base_color: rgb(0.8, 0.3, 0.1),
            metallic: c(0.3),
            eta: eta_of_specular(0.6),
            roughness: c(0.3),
            spec_tint: c(0.4),
            anisotropic: c(0.5),
            sheen: c(0.3),
            sheen_tint: c(0.2),
            clearcoat: c(0.6),
            clearcoat_gloss: c(0.3),
            flatness: c(0.4),
            ..principled_defaults()
        }),
        "principled_glass" => Material::Principled(Principled {
            base_color: rgb(0.9, 0.8, 0.7),
            spec_trans: c(0.8),
            eta: 1.4,
            roughness: c(0.4),
            metallic: c(0.1),
            sheen: c(0.5),
            ..principled_defaults()
        }),
        "principled_metal" => Material::Principled(Principled {
            base_color: rgb(0.9, 0.6, 0.2),
            metallic: c(1.0),
            roughness: c(0.2),
            anisotropic: c(0.3),
            ..principled_defaults()
        }),
        "principledthin_default" => Material::PrincipledThin(thin_defaults()),
        "principledthin_full" => Material::PrincipledThin(PrincipledThin {
            base_color: rgb(0.7, 0.1, 0.1),
            roughness: c(0.3),
            spec_tint: c(0.1),
            anisotropic: c(0.5),
            spec_trans: c(0.6),
            diff_trans: c(0.6),
            eta: c(1.33),
            sheen: c(0.5),
            sheen_tint: c(0.5),
            flatness: c(0.3),
            ..thin_defaults()
        }),
        "principledthin_clear" => Material::PrincipledThin(PrincipledThin {
            spec_trans: c(0.9),
            eta: c(1.5),
            roughness: c(0.4),
            ..thin_defaults()
        }),
        "dielectric" => Material::Dielectric(interface(1.5046)),
        "thindielectric" => Material::ThinDielectric(interface(1.5046)),
        "conductor" => Material::Conductor(metal),
        other => panic!("no material {other}"),
    }
}

#[test]
fn eval_and_pdf_match_mitsuba() {
    let mut failures = Vec::new();
    for &(name, wo, wi, f, pdf) in MITSUBA_REFERENCE {
        let b = build(&mitsuba_material(name));
        let (wo, wi) = (dir(wo.0, wo.1), dir(wi.0, wi.1));
        let ours = b.eval(wo, wi);
        let our_pdf = b.pdf(wo, wi);
        // Mitsuba computes in single precision (measured: within 5e-7 of ours), and fits
        // Beckmann's masking (within 0.35%; measured 0.32%).
        // The rough plastic's tables differ by up to 5e-4 (Mitsuba integrates in single
        // precision).
        let tol = if name.contains("beckmann") && !name.starts_with("roughplastic") {
            4e-3
        } else if name.starts_with("roughplastic") || name == "mask" {
            1e-3
        } else {
            2e-4
        };
        // Known difference: `principled` without transmission seen from the back samples
        // nothing and evaluates to 0 in both, but Mitsuba's `pdf` is not 0 there; ours is 0
        // (the density of what `sample` draws).
        let pdf = if name.starts_with("principled_") && wo.z < 0.0 && f == [0.0; 3] && our_pdf == 0.0 {
            0.0
        } else {
            pdf
        };
        if std::env::var_os("BSDF_REPORT").is_some() {
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-3);
            let worst = (0..3).map(|i| rel(ours[i], f[i])).fold(rel(our_pdf, pdf), f64::max);
            println!("{name}: relative difference {worst:.2e}");
        }
        let want = DVec3::from_array(f);
        let close = |a: f64, b: f64| (a - b).abs() <= tol * b.abs().max(1e-3);
        if !(0..3).all(|i| close(ours[i], want[i])) || !close(our_pdf, pdf) {
            failures.push(format!(
                "{name} wo={wo:.3} wi={wi:.3}: f {ours:.6} vs {want:.6}, pdf {our_pdf:.6} vs {pdf:.6}"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A delta reference: material name, `wo` as (theta, phi) in degrees, the number choosing the
/// lobe, and Mitsuba's `(wi, weight, pdf, eta)` when it drew a delta lobe.
type DeltaReference = (&'static str, (f64, f64), f64, Option<([f64; 3], [f64; 3], f64, f64)>);

/// `sample` of Mitsuba 3.9.1's delta BSDFs at fixed numbers (printed by the same script).
const MITSUBA_DELTA: &[DeltaReference] = &[
    (
        "dielectric",
        (30.0, 20.0),
        0.01,
        Some((
            [-4.698463082e-01, -1.710100770e-01, 8.660253882e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            4.2067781e-02,
            1.0000000e+00,
        )),
    ),
    (
        "dielectric",
        (30.0, 20.0),
        0.9,
        Some((
            [-3.123597503e-01, -1.136896610e-01, -9.431362748e-01],
            [4.4197583e-01, 4.4197583e-01, 4.4197583e-01],
            9.5793223e-01,
            1.5041833e+00,
        )),
    ),
    (
        "dielectric",
        (75.0, 100.0),
        0.05,
        Some((
            [1.677312553e-01, -9.512512684e-01, 2.588190436e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            2.5384167e-01,
            1.0000000e+00,
        )),
    ),
    (
        "dielectric",
        (75.0, 100.0),
        0.6,
        Some((
            [1.115098596e-01, -6.324038506e-01, -7.665708661e-01],
            [4.4197583e-01, 4.4197583e-01, 4.4197583e-01],
            7.4615836e-01,
            1.5041833e+00,
        )),
    ),
    (
        "dielectric",
        (150.0, 40.0),
        0.01,
        Some((
            [-3.830222189e-01, -3.213938177e-01, -8.660253882e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            5.6094684e-02,
            1.0000000e+00,
        )),
    ),
    (
        "dielectric",
        (150.0, 40.0),
        0.9,
        Some((
            [-5.761356354e-01, -4.834352136e-01, 6.590585113e-01],
            [2.2625673e+00, 2.2625673e+00, 2.2625673e+00],
            9.4390529e-01,
            6.6481262e-01,
        )),
    ),
    (
        "dielectric",
        (120.0, 200.0),
        0.5,
        Some((
            [8.137976527e-01, 2.961981297e-01, -5.000000000e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            1.0000000e+00,
            1.0000000e+00,
        )),
    ),
    (
        "thindielectric",
        (30.0, 20.0),
        0.01,
        Some((
            [-4.698463082e-01, -1.710100770e-01, 8.660253882e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            8.0739051e-02,
            1.0000000e+00,
        )),
    ),
    (
        "thindielectric",
        (30.0, 20.0),
        0.9,
        Some((
            [-4.698463082e-01, -1.710100770e-01, -8.660253882e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            9.1926098e-01,
            1.0000000e+00,
        )),
    ),
    (
        "thindielectric",
        (75.0, 100.0),
        0.05,
        Some((
            [1.677312553e-01, -9.512512684e-01, 2.588190436e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            4.0490228e-01,
            1.0000000e+00,
        )),
    ),
    (
        "thindielectric",
        (75.0, 100.0),
        0.6,
        Some((
            [1.677312553e-01, -9.512512684e-01, -2.588190436e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            5.9509772e-01,
            1.0000000e+00,
        )),
    ),
    (
        "thindielectric",
        (150.0, 40.0),
        0.01,
        Some((
            [-3.830222189e-01, -3.213938177e-01, -8.660253882e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            8.0739051e-02,
            1.0000000e+00,
        )),
    ),
    (
        "thindielectric",
        (150.0, 40.0),
        0.9,
        Some((
            [-3.830222189e-01, -3.213938177e-01, 8.660253882e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            9.1926098e-01,
            1.0000000e+00,
        )),
    ),
    (
        "thindielectric",
        (120.0, 200.0),
        0.5,
        Some((
            [8.137976527e-01, 2.961981297e-01, 5.000000000e-01],
            [1.0000000e+00, 1.0000000e+00, 1.0000000e+00],
            8.3506459e-01,
            1.0000000e+00,
        )),
    ),
    (
        "conductor",
        (30.0, 20.0),
        0.01,
        Some((
            [-4.698463082e-01, -1.710100770e-01, 8.660253882e-01],
            [9.6640015e-01, 8.0180931e-01, 3.2610497e-01],
            1.0000000e+00,
            1.0000000e+00,
        )),
    ),
    (
        "conductor",
        (30.0, 20.0),
        0.9,
        Some((
            [-4.698463082e-01, -1.710100770e-01, 8.660253882e-01],
            [9.6640015e-01, 8.0180931e-01, 3.2610497e-01],
            1.0000000e+00,
            1.0000000e+00,
        )),
    ),
    (
        "conductor",
        (75.0, 100.0),
        0.05,
        Some((
            [1.677312553e-01, -9.512512684e-01, 2.588190436e-01],
            [9.5923960e-01, 8.4127969e-01, 4.9570394e-01],
            1.0000000e+00,
            1.0000000e+00,
        )),
    ),
    (
        "conductor",
        (75.0, 100.0),
        0.6,
        Some((
            [1.677312553e-01, -9.512512684e-01, 2.588190436e-01],
            [9.5923960e-01, 8.4127969e-01, 4.9570394e-01],
            1.0000000e+00,
            1.0000000e+00,
        )),
    ),
    ("conductor", (150.0, 40.0), 0.01, None),
    ("conductor", (150.0, 40.0), 0.9, None),
    ("conductor", (120.0, 200.0), 0.5, None),
    (
        "plastic",
        (30.0, 20.0),
        0.01,
        Some((
            [-4.698463082e-01, -1.710100770e-01, 8.660253882e-01],
            [3.6011535e-01, 3.6011535e-01, 3.6011535e-01],
            1.1155581e-01,
            1.0000000e+00,
        )),
    ),
    ("plastic", (30.0, 20.0), 0.9, None),
    (
        "plastic",
        (75.0, 100.0),
        0.05,
        Some((
            [1.677312553e-01, -9.512512684e-01, 2.588190436e-01],
            [5.0071770e-01, 5.0071770e-01, 5.0071770e-01],
            5.0143331e-01,
            1.0000000e+00,
        )),
    ),
    ("plastic", (75.0, 100.0), 0.6, None),
    ("plastic", (150.0, 40.0), 0.01, None),
    ("plastic", (150.0, 40.0), 0.9, None),
    ("plastic", (120.0, 200.0), 0.5, None),
];

#[test]
fn delta_samples_match_mitsuba() {
    let mut failures = Vec::new();
    for &(name, wo, u, want) in MITSUBA_DELTA {
        let b = build(&mitsuba_material(name));
        let wo = dir(wo.0, wo.1);
        let ours = b.sample(wo, u, 0.5, 0.5).filter(|s| s.delta);
        match (ours, want) {
            (None, None) => {}
            (Some(s), Some((wi, weight, pdf, eta))) => {
                let ok = (s.wi - DVec3::from_array(wi)).abs().max_element() < 1e-6
                    && (s.weight - DVec3::from_array(weight)).abs().max_element() < 1e-6 * weight[0].max(1.0)
                    && (s.pdf - pdf).abs() < 1e-6
                    && (s.eta - eta).abs() < 1e-6;
                if !ok {
                    failures.push(format!("{name} wo={wo:.3} u={u}: {s:?} vs {wi:?} {weight:?} {pdf} {eta}"));
                }
            }
            (ours, want) => failures.push(format!("{name} wo={wo:.3} u={u}: {ours:?} vs {want:?}")),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn degenerate_directions_give_finite_non_negative_values() {
    // Grazing (z = 0), the poles, and tiny roughness: never NaN, never negative, never a panic.
    let mut materials: Vec<Material> = variants().into_iter().map(|(_, m, _)| m).collect();
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        let mf = microfacet(kind, 0.0, 1e-9, true);
        materials.push(Material::RoughConductor { metal: gold(), microfacet: mf.clone() });
        materials.push(Material::RoughDielectric { interface: interface(1.5046), microfacet: mf.clone() });
        materials.push(Material::RoughPlastic { coating: coating(c(0.5)), microfacet: mf });
    }
    let special = [
        DVec3::Z,
        -DVec3::Z,
        DVec3::X,
        DVec3::new(0.6, 0.8, 0.0),
        dir(89.999_999, 10.0),
        dir(90.000_001, 10.0),
    ];
    let mut rng = Pcg64Mcg::seed_from_u64(99);
    for m in &materials {
        let b = build(m);
        for &wo in &special {
            for &wi in &special {
                let f = b.eval(wo, wi);
                let p = b.pdf(wo, wi);
                assert!(
                    f.is_finite() && f.min_element() >= 0.0 && p.is_finite() && p >= 0.0,
                    "{m:?} {wo} {wi}"
                );
            }
            for u in [0.0, 0.5, 1.0 - f64::EPSILON] {
                for _ in 0..20 {
                    if let Some(s) = b.sample(wo, u, rng.random(), rng.random()) {
                        assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0, "{m:?} {wo}: {s:?}");
                        assert!(
                            s.pdf.is_finite() && s.pdf > 0.0 && s.eta.is_finite() && s.eta > 0.0,
                            "{s:?}"
                        );
                        assert!(s.wi.is_finite(), "{s:?}");
                    }
                }
                for (u1, u2) in [(0.0, 0.0), (1.0 - f64::EPSILON, 1.0 - f64::EPSILON)] {
                    if let Some(s) = b.sample(wo, u, u1, u2) {
                        assert!(
                            s.weight.is_finite() && s.pdf.is_finite() && s.wi.is_finite(),
                            "{m:?} {wo}: {s:?}"
                        );
                    }
                }
            }
        }
    }
}
