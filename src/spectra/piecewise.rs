//! Piecewise-linear spectra: pbrt-v4's `PiecewiseLinearSpectrum`, built from inline
//! `"spectrum"` (wavelength, value) pairs, `.spd` files and the named-spectrum tables.

use std::path::Path;

use super::SpectrumError;

/// A spectrum given by samples at increasing wavelengths (nm), linearly interpolated between
/// them and zero outside them — exactly as pbrt-v4 evaluates it.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseLinearSpectrum {
    lambdas: Vec<f64>,
    values: Vec<f64>,
}

impl PiecewiseLinearSpectrum {
    /// Builds a spectrum from (wavelength, value) pairs; wavelengths must strictly increase
    /// (pbrt-v4 rejects anything else). `origin` names the source in error messages.
    pub fn from_pairs(
        pairs: impl IntoIterator<Item = (f64, f64)>,
        origin: &str,
    ) -> Result<PiecewiseLinearSpectrum, SpectrumError> {
        let (lambdas, values): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
        let invalid = |message: String| SpectrumError::Invalid { origin: origin.to_string(), message };
        if lambdas.is_empty() {
            return Err(invalid("no samples".to_string()));
        }
        if let Some(bad) = lambdas.iter().chain(&values).find(|v| !v.is_finite()) {
            return Err(invalid(format!("sample {bad} is not a finite number")));
        }
        if let Some(i) = (1..lambdas.len()).find(|&i| lambdas[i] <= lambdas[i - 1]) {
            return Err(invalid(format!(
                "wavelengths must increase, but entry {} ({} nm) follows {} nm",
                i + 1,
                lambdas[i],
                lambdas[i - 1]
            )));
        }
        Ok(PiecewiseLinearSpectrum { lambdas, values })
    }

    /// Builds a spectrum from interleaved `wavelength value` numbers (the layout of inline
    /// `"spectrum"` parameters and `.spd` files).
    pub fn from_interleaved(values: &[f64], origin: &str) -> Result<PiecewiseLinearSpectrum, SpectrumError> {
        if !values.len().is_multiple_of(2) {
            return Err(SpectrumError::Invalid {
                origin: origin.to_string(),
                message: format!("{} numbers: wavelength/value pairs need an even count", values.len()),
            });
        }
        Self::from_pairs(values.chunks_exact(2).map(|p| (p[0], p[1])), origin)
    }

    /// Parses the text of a spectrum file: numbers separated by whitespace or commas, read as
    /// `wavelength value` pairs; `#` starts a comment that runs to the end of the line.
    pub fn parse(text: &str, origin: &str) -> Result<PiecewiseLinearSpectrum, SpectrumError> {
        let numbers =
            parse_numbers(text).map_err(|message| SpectrumError::Invalid { origin: origin.to_string(), message })?;
        Self::from_interleaved(&numbers, origin)
    }

    /// Reads a `.spd` file. Any problem (unreadable file, stray text, odd count, wavelengths
    /// that do not increase) is an error naming the file.
    pub fn read(path: &Path) -> Result<PiecewiseLinearSpectrum, SpectrumError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| SpectrumError::Read { path: path.to_path_buf(), source })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// The value at `lambda` nm: linear between samples, 0 outside them. A single sample is
    /// zero everywhere, as it is for pbrt-v4's continuously sampled wavelengths.
    pub fn eval(&self, lambda: f64) -> f64 {
        let n = self.lambdas.len();
        if n < 2 || lambda < self.lambdas[0] || lambda > self.lambdas[n - 1] {
            return 0.0;
        }
        // Index of the last sample at or below lambda, kept one short of the end so the
        // last wavelength interpolates within the final segment.
        let i = self.lambdas.partition_point(|&l| l <= lambda).clamp(1, n - 1) - 1;
        let t = (lambda - self.lambdas[i]) / (self.lambdas[i + 1] - self.lambdas[i]);
        self.values[i] + t * (self.values[i + 1] - self.values[i])
    }

    /// The sample wavelengths (nm).
    pub fn lambdas(&self) -> &[f64] {
        &self.lambdas
    }

    /// The sample values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The largest sample value.
    pub fn max_value(&self) -> f64 {
        self.values.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    /// Multiplies every value by `s`.
    pub fn scale(&mut self, s: f64) {
        self.values.iter_mut().for_each(|v| *v *= s);
    }

    /// Extends the first and last values as constants just past `[lo, hi]`, as pbrt-v4's
    /// `FromInterleaved` does for its named spectra so they cover the visible range.
    pub(crate) fn extend_to(&mut self, lo: f64, hi: f64) {
        if self.lambdas[0] > lo {
            self.lambdas.insert(0, lo - 1.0);
            self.values.insert(0, self.values[0]);
        }
        if self.lambdas[self.lambdas.len() - 1] < hi {
            self.lambdas.push(hi + 1.0);
            self.values.push(self.values[self.values.len() - 1]);
        }
    }
}

/// Splits text into numbers: separators are whitespace and commas, `#` comments run to the
/// end of the line. A token that is not a number is an error naming its line.
pub(crate) fn parse_numbers(text: &str) -> Result<Vec<f64>, String> {
    let mut numbers = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        for token in line.split(|c: char| c.is_whitespace() || c == ',') {
            if token.is_empty() {
                continue;
            }
            match token.parse::<f64>() {
                Ok(v) if v.is_finite() => numbers.push(v),
                _ => {
                    return Err(format!("line {}: \"{token}\" is not a number", line_no + 1));
                }
            }
        }
    }
    if numbers.is_empty() {
        return Err("no numbers found".to_string());
    }
    Ok(numbers)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd(text: &str) -> Result<PiecewiseLinearSpectrum, SpectrumError> {
        PiecewiseLinearSpectrum::parse(text, "test.spd")
    }

    #[test]
    fn interpolates_linearly_and_is_zero_outside() {
        let s = spd("400 1\n500 3\n600 2\n").unwrap();
        assert_eq!(s.eval(400.0), 1.0);
        assert_eq!(s.eval(450.0), 2.0);
        assert_eq!(s.eval(500.0), 3.0);
        assert_eq!(s.eval(600.0), 2.0);
        assert_eq!(s.eval(399.9), 0.0);
        assert_eq!(s.eval(600.1), 0.0);
    }

    #[test]
    fn parses_comments_commas_and_blank_lines() {
        let s = spd("# measured\n\n400 0.5 # first\n500, 0.75\n  600\t1.0\n").unwrap();
        assert_eq!(s.lambdas(), &[400.0, 500.0, 600.0]);
        assert_eq!(s.values(), &[0.5, 0.75, 1.0]);
    }

    #[test]
    fn rejects_malformed_files() {
        let msg = |t: &str| spd(t).unwrap_err().to_string();
        assert!(msg("400 1 500").contains("even count"), "{}", msg("400 1 500"));
        assert!(msg("500 1\n400 2\n").contains("must increase"));
        assert!(msg("500 1\n500 2\n").contains("must increase"));
        assert!(msg("# nothing\n").contains("no numbers"));
        let m = msg("400 1\n500 abc\n");
        assert!(m.starts_with("test.spd: line 2"), "{m}");
    }

    #[test]
    fn missing_file_is_a_read_error_naming_it() {
        let path = Path::new("/nonexistent/dir/missing.spd");
        let err = PiecewiseLinearSpectrum::read(path).unwrap_err();
        assert!(matches!(err, SpectrumError::Read { .. }));
        assert!(err.to_string().contains("missing.spd"), "{err}");
    }

    #[test]
    fn reads_a_file_from_disk() {
        let path = std::env::temp_dir().join(format!("nimbus-spectra-{}.spd", std::process::id()));
        std::fs::write(&path, "# test\n300 0\n800 1\n").unwrap();
        let s = PiecewiseLinearSpectrum::read(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert!((s.eval(550.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn single_sample_is_zero() {
        let s = PiecewiseLinearSpectrum::from_pairs([(550.0, 1.0)], "inline").unwrap();
        assert_eq!(s.eval(550.0), 0.0);
    }

    #[test]
    fn extension_repeats_end_values() {
        let mut s = spd("400 2\n700 3\n").unwrap();
        s.extend_to(360.0, 830.0);
        assert_eq!(s.eval(360.0), 2.0);
        assert_eq!(s.eval(830.0), 3.0);
        assert_eq!(s.eval(358.0), 0.0);
    }
}
