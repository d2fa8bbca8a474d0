//! `<spectrum>` values: a uniform value or `wavelength:value` samples, and their reduction to
//! linear sRGB as Mitsuba 3's RGB variants (`scalar_rgb`, `llvm_ad_rgb`) reduce them.

use glam::DVec3;

use super::cie::{CIE_MAX, CIE_MIN, CIE_Y_NORMALIZATION, cie_d65, cie1931_xyz, xyz_to_srgb};

/// Most samples a spectrum may have (a `.spd` file of 1 nm samples over the visible range
/// has about 500).
pub const MAX_SPECTRUM_SAMPLES: usize = 100_000;

/// A spectrum as a scene file gives it. Wavelengths are in nanometres.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// `value="0.5"`: the same value at every wavelength.
    Uniform(f64),
    /// `value="400:0.1, 500:0.2, ..."` or `filename="x.spd"`: at least two samples, wavelengths
    /// strictly increasing, linearly interpolated between them and zero outside.
    Sampled {
        /// Wavelengths, nm, strictly increasing.
        wavelengths: Vec<f64>,
        /// The values at those wavelengths.
        values: Vec<f64>,
    },
}

/// What a spectrum is used for, which decides how Mitsuba's RGB variants reduce it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumUse {
    /// A reflectance or other quantity in [0, 1] (`reflectance`, `specular_reflectance`...):
    /// integrated under D65 and clamped to [0, 1].
    Bounded,
    /// An unbounded non-emitted quantity (Mitsuba: the parameters `eta`, `k`, `int_ior`,
    /// `ext_ior`): integrated under D65, negative components clamped to 0.
    Unbounded,
    /// Emitted radiance or irradiance (a spectrum inside an `<emitter>`): integrated without
    /// D65, negative components clamped to 0.
    Emission,
}

impl SpectrumUse {
    /// The use Mitsuba gives a spectrum called `name`, inside an emitter or not.
    pub fn of(name: &str, within_emitter: bool) -> SpectrumUse {
        if within_emitter {
            SpectrumUse::Emission
        } else if matches!(name, "eta" | "k" | "int_ior" | "ext_ior") {
            SpectrumUse::Unbounded
        } else {
            SpectrumUse::Bounded
        }
    }
}

impl Spectrum {
    /// Parses a `value` attribute: one number (uniform) or `wavelength:value` pairs separated
    /// by commas or spaces, as Mitsuba's `Properties::Spectrum` does. Errors are one-line
    /// messages (the caller adds the place).
    pub fn parse(text: &str) -> Result<Spectrum, String> {
        let tokens: Vec<&str> = super::numbers::tokens(text).collect();
        if let [only] = tokens[..]
            && !only.contains(':')
        {
            return super::numbers::float(only)
                .map(Spectrum::Uniform)
                .ok_or_else(|| format!("`{only}` is not a finite number"));
        }
        if tokens.len() > MAX_SPECTRUM_SAMPLES {
            return Err(format!("a spectrum has at most {MAX_SPECTRUM_SAMPLES} samples"));
        }
        let mut wavelengths = Vec::with_capacity(tokens.len());
        let mut values = Vec::with_capacity(tokens.len());
        for token in tokens {
            let pair = token.split_once(':').and_then(|(w, v)| {
                Some((super::numbers::float(w.trim())?, super::numbers::float(v.trim())?))
            });
            let Some((w, v)) = pair else {
                return Err(format!("`{token}` is not a wavelength:value pair of finite numbers"));
            };
            wavelengths.push(w);
            values.push(v);
        }
        Spectrum::sampled(wavelengths, values)
    }

    /// Parses the text of a `.spd` file: one `wavelength value` pair a line, `#` comments and
    /// blank lines skipped. Errors name the line.
    pub fn parse_spd(text: &str) -> Result<Spectrum, String> {
        let mut wavelengths = Vec::new();
        let mut values = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            if wavelengths.len() >= MAX_SPECTRUM_SAMPLES {
                return Err(format!("a spectrum has at most {MAX_SPECTRUM_SAMPLES} samples"));
            }
            let fields: Vec<&str> = line.split_whitespace().collect();
            let pair = match fields[..] {
                [w, v] => super::numbers::float(w).zip(super::numbers::float(v)),
                _ => None,
            };
            let Some((w, v)) = pair else {
                return Err(format!("line {}: expected `wavelength value`, found `{line}`", i + 1));
            };
            wavelengths.push(w);
            values.push(v);
        }
        Spectrum::sampled(wavelengths, values)
    }

    /// A sampled spectrum, checked: at least two samples, wavelengths strictly increasing.
    pub fn sampled(wavelengths: Vec<f64>, values: Vec<f64>) -> Result<Spectrum, String> {
        if wavelengths.len() < 2 || wavelengths.len() != values.len() {
            return Err("a sampled spectrum needs at least two wavelength:value pairs".into());
        }
        if wavelengths.windows(2).any(|w| w[1] <= w[0]) {
            return Err("the wavelengths of a spectrum must be strictly increasing".into());
        }
        Ok(Spectrum::Sampled { wavelengths, values })
    }

    /// The linear sRGB colour Mitsuba 3's RGB variants give this spectrum when it is used as
    /// `usage` (its `Properties::get_texture_impl` in 3.9):
    ///
    /// - uniform `v`: `(v, v, v)`, except for emission, where it is `v` times the sRGB of the
    ///   equal-energy white (`xyz_to_srgb(1, 1, 1)`, a little purple), as spectral variants
    ///   would render it;
    /// - sampled: [`spectrum_list_to_srgb`], with D65 unless emitted, clamped to [0, 1] when
    ///   bounded and at 0 otherwise.
    pub fn to_srgb(&self, usage: SpectrumUse) -> DVec3 {
        match self {
            Spectrum::Uniform(v) => match usage {
                SpectrumUse::Emission => DVec3::from(xyz_to_srgb([1.0; 3])) * *v,
                SpectrumUse::Bounded | SpectrumUse::Unbounded => DVec3::splat(*v),
            },
            Spectrum::Sampled { wavelengths, values } => spectrum_list_to_srgb(
                wavelengths,
                values,
                usage == SpectrumUse::Bounded,
                usage != SpectrumUse::Emission,
            ),
        }
    }
}

/// Reduces a sampled spectrum to linear sRGB as Mitsuba's `spectrum_list_to_srgb` does: 1000
/// evenly spaced wavelengths over [360, 830] nm, the spectrum linearly interpolated (zero outside
/// its samples), weighted by the CIE 1931 curves (and by D65, scaled to luminance 1, when `d65`),
/// scaled so that a unit spectrum has luminance 1, then XYZ to sRGB. With `bounded` the result
/// is clamped to [0, 1], otherwise only negative components are raised to 0.
///
/// `wavelengths` must be strictly increasing and as long as `values` (see [`Spectrum::sampled`]).
pub fn spectrum_list_to_srgb(wavelengths: &[f64], values: &[f64], bounded: bool, d65: bool) -> DVec3 {
    const STEPS: usize = 1000;
    let (Some(&first), Some(&last)) = (wavelengths.first(), wavelengths.last()) else {
        return DVec3::ZERO;
    };
    let n = wavelengths.len().min(values.len());
    if n < 2 {
        return DVec3::ZERO;
    }
    let mut xyz = [0.0f64; 3];
    let mut index = 0usize;
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        // The last interval whose start is at most `w` (the wavelengths only grow with `i`).
        while index + 2 < n && wavelengths[index + 1] <= w {
            index += 1;
        }
        let (w0, w1, v0, v1) = (wavelengths[index], wavelengths[index + 1], values[index], values[index + 1]);
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let weight = v * if d65 { cie_d65(w) } else { 1.0 };
        let cmf = cie1931_xyz(w);
        for k in 0..3 {
            xyz[k] += cmf[k] * weight;
        }
    }
    let scale = (CIE_MAX - CIE_MIN) / STEPS as f64 * CIE_Y_NORMALIZATION;
    let rgb = DVec3::from(xyz_to_srgb(xyz.map(|c| c * scale)));
    if bounded { rgb.clamp(DVec3::ZERO, DVec3::ONE) } else { rgb.max(DVec3::ZERO) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: [f64; 3]) {
        // Mitsuba computes in single precision.
        assert!((a - DVec3::from(b)).abs().max_element() < 2e-5, "{a} vs {b:?}");
    }

    // The expected colours were printed by Mitsuba 3.9.1 (`scalar_rgb`): `mi.traverse` of a
    // diffuse `reflectance`, an area emitter's `radiance` and a conductor's `eta` and `k` given
    // these spectra (see docs/mitsuba-format.md).
    #[test]
    fn sampled_spectra_reduce_as_mitsuba_rgb_variants() {
        let s = Spectrum::parse("400:0.2, 500:0.5, 600:0.8, 700:0.3").expect("spectrum");
        close(s.to_srgb(SpectrumUse::Bounded), [0.755029, 0.641416, 0.323239]);
        close(s.to_srgb(SpectrumUse::Emission), [0.886932, 0.614419, 0.285147]);
        let eta = Spectrum::parse("400:0.2 500:0.5 600:2.8 700:0.3").expect("spectrum");
        close(eta.to_srgb(SpectrumUse::of("eta", false)), [2.80724, 1.48682, 0.189414]);
        let k = Spectrum::parse("400:3.2, 500:2.5, 600:2.8, 700:1.3").expect("spectrum");
        close(k.to_srgb(SpectrumUse::of("k", false)), [2.56443, 2.6182, 2.83065]);
    }

    #[test]
    fn uniform_spectra_are_grey_except_when_emitted() {
        let s = Spectrum::parse("2").expect("uniform");
        assert_eq!(s, Spectrum::Uniform(2.0));
        close(s.to_srgb(SpectrumUse::Emission), [2.40959, 1.89658, 1.81783]);
        assert_eq!(s.to_srgb(SpectrumUse::Bounded), DVec3::splat(2.0));
    }

    #[test]
    fn a_flat_reflectance_is_white_and_clamped() {
        let s = Spectrum::parse("360:1, 830:1").expect("spectrum");
        let rgb = s.to_srgb(SpectrumUse::Unbounded);
        assert!((rgb - DVec3::ONE).abs().max_element() < 0.01, "{rgb}");
        let bright = Spectrum::parse("360:3, 830:3").expect("spectrum");
        assert!(bright.to_srgb(SpectrumUse::Bounded).max_element() <= 1.0);
    }

    #[test]
    fn malformed_spectra_are_refused() {
        for bad in
            ["", "400:0.1", "500:1, 400:2", "400:1, 400:2", "400-1, 500:2", "x", "400:1:2, 500:1", "nan"]
        {
            assert!(Spectrum::parse(bad).is_err(), "{bad:?}");
        }
        let err = Spectrum::parse_spd("# c\n400 1\n500\n").expect_err("short line");
        assert!(err.starts_with("line 3:"), "{err}");
        let ok = Spectrum::parse_spd("# comment\n\n400 1 # note\r\n500 2\n").expect("spd");
        assert_eq!(ok, Spectrum::Sampled { wavelengths: vec![400.0, 500.0], values: vec![1.0, 2.0] });
    }
}
