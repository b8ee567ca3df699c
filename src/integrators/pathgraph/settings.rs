//! `pathgraph` parameters: the path loop's `maxdepth` and `regularize` (shared with
//! `volpath`, so switching a volpath scene to pathgraph keeps its paths) and the graph's
//! cluster size, iteration count, extra first-vertex light samples and extra first vertices
//! along the camera ray, and whether pixels
//! combine the graph's estimate with their paths' unbiased one.

use nimbus_parser::{Entity, Error};

/// `pathgraph` parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct PathGraphSettings {
    /// Maximum number of scattering events (`integer maxdepth`, default 5 as pbrt-v4's volpath).
    pub max_depth: u32,
    /// Roughen near-specular BSDFs after the first non-specular bounce (`bool regularize`).
    pub regularize: bool,
    /// Expected shading points per cluster, K (`integer clustersize`, default 16: of the K that
    /// keep every pbrt-scenes media scene's mean within 1 % of volpath's, the one with the
    /// lowest equal-time MSE in the K study on the cloud, the wax and the fog; K 32 is 4 %
    /// lower there but puts emissive-smoke at −1.1 %, README). 1 makes every point its
    /// own cluster: the image is then volpath's (with lights seen through media estimated by
    /// transmittance, `PathConfig::camera_line`).
    pub cluster_size: u32,
    /// Aggregation + propagation rounds of Eq. 28 (`integer iterations`).
    pub iterations: u32,
    /// Extra light samples at each path's first vertex, used for the pixel's direct light
    /// instead of the path's own (`integer extradirect`, Sec. 4; 0 = the path's own).
    pub extra_direct: u32,
    /// Extra first vertices along each camera ray, each with a light sample, whose mean with
    /// the path's own is the pixel's direct light (`integer linesamples`; absent: chosen after
    /// two samples from the measured noise, `line.rs`).
    pub line_samples: Option<u32>,
    /// Combine each pixel's graph estimate with the unbiased path-traced estimate its own
    /// paths carry, trusting the graph as far as the two agree (`bool combine`, default true;
    /// README: consistency). False: the graph's estimate alone, as in the paper, whose bias
    /// does not fall with the sample count.
    pub combine: bool,
}

impl Default for PathGraphSettings {
    fn default() -> Self {
        PathGraphSettings {
            max_depth: 5,
            regularize: false,
            cluster_size: 16,
            iterations: 2,
            extra_direct: 0,
            line_samples: None,
            combine: true,
        }
    }
}

impl PathGraphSettings {
    /// Reads the parameters.
    pub fn from_entity(e: &Entity) -> Result<PathGraphSettings, Error> {
        let p = &e.params;
        let d = PathGraphSettings::default();
        let count = |name: &str, default: u32, min: i32, max: i32| -> Result<u32, Error> {
            let v = p.get_one_int(name, default as i32)?;
            if v < min || v > max {
                return Err(Error::new(
                    p.loc(name).unwrap_or(&e.loc),
                    format!("\"{name}\" must be between {min} and {max} (it is {v})"),
                ));
            }
            Ok(v as u32)
        };
        Ok(PathGraphSettings {
            max_depth: count("maxdepth", d.max_depth, 0, 100_000)?,
            regularize: p.get_one_bool("regularize", d.regularize)?,
            cluster_size: count("clustersize", d.cluster_size, 1, 4096)?,
            iterations: count("iterations", d.iterations, 0, 1000)?,
            extra_direct: count("extradirect", d.extra_direct, 0, 4096)?,
            line_samples: match p.loc("linesamples") {
                None => None,
                Some(_) => Some(count("linesamples", 0, 0, 1024)?),
            },
            combine: p.get_one_bool("combine", d.combine)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(params: &str) -> Result<PathGraphSettings, Error> {
        let text = format!("Integrator \"pathgraph\" {params}\nWorldBegin\n");
        let desc = nimbus_parser::load_str(&text, "test.pbrt").unwrap();
        PathGraphSettings::from_entity(&desc.integrator)
    }

    #[test]
    fn defaults_and_overrides() {
        assert_eq!(read("").unwrap(), PathGraphSettings::default());
        let s = read(r#""integer maxdepth" 12 "integer clustersize" 1 "integer iterations" 0 "integer extradirect" 4"#)
            .unwrap();
        assert_eq!((s.max_depth, s.cluster_size, s.iterations, s.extra_direct), (12, 1, 0, 4));
        assert_eq!(s.line_samples, None);
        assert_eq!(read(r#""integer linesamples" 0"#).unwrap().line_samples, Some(0));
        assert_eq!(read(r#""integer linesamples" 8"#).unwrap().line_samples, Some(8));
        assert!(read(r#""integer linesamples" -1"#).unwrap_err().to_string().contains("linesamples"));
    }

    #[test]
    fn out_of_range_and_wrong_types_name_the_parameter() {
        let e = read(r#""integer clustersize" 0"#).unwrap_err().to_string();
        assert!(e.contains("clustersize") && e.contains("test.pbrt:1"), "{e}");
        let e = read(r#""float iterations" 2"#).unwrap_err().to_string();
        assert!(e.contains("iterations"), "{e}");
    }
}
