//! `nimbus compare --html report.html`: one self-contained page (nothing fetched from a
//! network) with the reference, every method and its false-colour error side by side, a large
//! flip view switched with the number keys, synchronized zoom and pan, pixel values on hover,
//! error-vs-time charts (log-log SVG drawn by the page, values on hover), the results table
//! and notes.
//!
//! The page's script and style are `report.js` and `report.css` beside this file. Pixels travel
//! as base64 little-endian Float32 in one JSON block; the script decodes them and tone-maps them
//! (exposure, sRGB). On load it checks itself (a view per image, no script errors, number keys
//! switch the flip view, a path per chart series) and writes the verdict to
//! `<body data-selfcheck="pass">` or `"fail: <why>"`; `tests/browser/report.sh` reads it in a
//! headless Chromium.
//!
//! The data model below is all the page knows: it does not depend on `Comparison`.

use std::path::Path;

use anyhow::{Context, Result};
use serde_json::{Value, json};

/// A linear-RGB image, row-major, 3 floats per pixel.
pub struct HtmlImage {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// `width × height × 3` floats, row by row from the top.
    pub rgb: Vec<f32>,
}

/// One compared method: its final image and what its table row / caption says.
pub struct HtmlMethod {
    /// E.g. "pathgraph (seed 1)".
    pub name: String,
    /// Short text under the image, e.g. "relMSE 1.2e-3 ± 1e-4, 20 s".
    pub caption: String,
    /// Its final image, the reference's size.
    pub image: HtmlImage,
}

/// One curve of the error-vs-time chart.
pub struct HtmlSeries {
    /// Legend text.
    pub name: String,
    /// A CSS colour.
    pub color: String,
    /// (seconds, error); points that a log axis cannot show (≤ 0, not finite) are left out.
    pub points: Vec<(f64, f64)>,
}

/// An error-vs-time chart with log-log axes.
pub struct HtmlChart {
    /// Above the chart.
    pub title: String,
    /// Under the x axis.
    pub x_label: String,
    /// Beside the y axis.
    pub y_label: String,
    /// One line with markers each.
    pub series: Vec<HtmlSeries>,
}

/// A table of text cells.
pub struct HtmlTable {
    /// Column heads.
    pub headers: Vec<String>,
    /// Rows of cells.
    pub rows: Vec<Vec<String>>,
}

/// Everything the page shows.
pub struct HtmlReport {
    /// The page's title and heading.
    pub title: String,
    /// Paragraphs of plain text.
    pub notes: Vec<String>,
    /// What every method is measured against.
    pub reference: HtmlImage,
    /// The compared methods, in the order of the number keys 1..9.
    pub methods: Vec<HtmlMethod>,
    /// Error against time.
    pub charts: Vec<HtmlChart>,
    /// The results.
    pub table: HtmlTable,
}

const SCRIPT: &str = include_str!("report.js");
const STYLE: &str = include_str!("report.css");

/// The page's first script: it records every error, unhandled rejection and `console.error`
/// before anything else runs, for the self-check (and marks the page failed at once).
const ERROR_TRAP: &str = "window.__nimbusErrors = [];\n\
window.__nimbusFail = function (what) {\n\
  window.__nimbusErrors.push(what);\n\
  if (document.body) document.body.dataset.selfcheck = 'fail: ' + what;\n\
};\n\
window.onerror = function (msg, src, line) { window.__nimbusFail(msg + ' (line ' + line + ')'); };\n\
window.addEventListener('unhandledrejection', function (e) { window.__nimbusFail('unhandled rejection: ' + e.reason); });\n\
(function (original) {\n\
  console.error = function () {\n\
    window.__nimbusFail('console.error: ' + Array.prototype.join.call(arguments, ' '));\n\
    return original.apply(console, arguments);\n\
  };\n\
})(console.error);\n";

/// Writes the report as one HTML file. Every method's image must have the reference's size.
pub fn write(report: &HtmlReport, path: &Path) -> Result<()> {
    let page = page(report)?;
    std::fs::write(path, page).with_context(|| format!("writing {}", path.display()))
}

fn check_image(image: &HtmlImage, what: &str) -> Result<()> {
    anyhow::ensure!(
        image.rgb.len() == image.width * image.height * 3,
        "{what} has {} floats, not 3 per pixel of {}×{}",
        image.rgb.len(),
        image.width,
        image.height
    );
    Ok(())
}

fn check_sizes(report: &HtmlReport) -> Result<()> {
    let r = &report.reference;
    anyhow::ensure!(r.width > 0 && r.height > 0, "the reference image is empty ({}×{})", r.width, r.height);
    check_image(r, "the reference image")?;
    for m in &report.methods {
        let i = &m.image;
        anyhow::ensure!(
            i.width == r.width && i.height == r.height,
            "method \"{}\": its image is {}×{} but the reference is {}×{}",
            m.name,
            i.width,
            i.height,
            r.width,
            r.height
        );
        check_image(i, &format!("method \"{}\"'s image", m.name))?;
    }
    Ok(())
}

/// The whole page as text.
fn page(report: &HtmlReport) -> Result<String> {
    check_sizes(report)?;
    let title = escape(&report.title);
    let mut charts = String::new();
    for (i, c) in report.charts.iter().enumerate() {
        charts.push_str(&format!(
            "<figure class=\"chart\"><svg class=\"chart-svg\" data-chart=\"{i}\" role=\"img\" aria-label=\"{}\"></svg>\
             <div class=\"tooltip\" hidden></div></figure>\n",
            escape(&c.title)
        ));
    }
    let notes: String = report.notes.iter().map(|p| format!("<p>{}</p>\n", escape(p))).collect();
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>{title}</title>\n<script>\n{ERROR_TRAP}</script>\n<style>\n{STYLE}</style>\n</head>\n<body>\n\
         <h1>{title}</h1>\n<p id=\"selfcheck-status\" class=\"status\"></p>\n{CONTROLS}\
         <section id=\"gallery\" aria-label=\"reference, methods and errors\"></section>\n\
         <section id=\"charts\">\n{charts}</section>\n<section id=\"results\">\n{table}</section>\n\
         <section id=\"notes\">\n{notes}</section>\n\
         <script type=\"application/json\" id=\"nimbus-data\">{data}</script>\n<script>\n{SCRIPT}</script>\n\
         </body>\n</html>\n",
        table = table_html(&report.table),
        data = data_json(report),
    ))
}

/// The flip view, the controls and the pixel panel; the script fills them in.
const CONTROLS: &str = "<section id=\"viewer\">\n\
<div id=\"flip-wrap\"><div id=\"flip-label\" aria-live=\"polite\"></div>\
<canvas id=\"flip\" class=\"view\" data-kind=\"flip\"></canvas><div id=\"flip-buttons\"></div></div>\n\
<div id=\"side\">\n<div id=\"controls\">\n\
<label>exposure <input id=\"exposure\" type=\"range\" min=\"-10\" max=\"10\" step=\"0.25\" value=\"0\"> \
<output id=\"exposure-value\"></output></label>\n\
<label>error scale <input id=\"error-scale\" type=\"range\" step=\"0.05\"> <output id=\"error-scale-value\"></output></label>\n\
<div class=\"error-legend\"><span>darker</span><span class=\"ramp\"></span><span>brighter</span></div>\n\
<button id=\"reset\" type=\"button\">reset view (r)</button>\n\
<p class=\"help\">Keys: <kbd>0</kbd> reference, <kbd>1</kbd>–<kbd>9</kbd> methods, <kbd>e</kbd> image / error, \
<kbd>r</kbd> reset, <kbd>+</kbd>/<kbd>-</kbd> exposure. Wheel zooms, drag pans (all views together). \
Error: method − reference, mean of the channels.</p>\n</div>\n\
<div id=\"pixel-info\"><p class=\"help\">Hover an image for pixel values.</p></div>\n</div>\n</section>\n";

fn table_html(table: &HtmlTable) -> String {
    let mut s = String::from("<table>\n<thead><tr>");
    for h in &table.headers {
        s.push_str(&format!("<th>{}</th>", escape(h)));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for row in &table.rows {
        s.push_str("<tr>");
        for cell in row {
            s.push_str(&format!("<td>{}</td>", escape(cell)));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table>\n");
    s
}

fn image_json(name: &str, caption: &str, image: &HtmlImage) -> Value {
    let bytes: Vec<u8> = image.rgb.iter().flat_map(|v| v.to_le_bytes()).collect();
    json!({
        "name": name,
        "caption": caption,
        "width": image.width,
        "height": image.height,
        "rgb": base64(&bytes),
    })
}

/// The data block: names, captions, pixels and chart points, safe inside `<script>`.
fn data_json(report: &HtmlReport) -> String {
    let charts: Vec<Value> = report
        .charts
        .iter()
        .map(|c| {
            let series: Vec<Value> = c
                .series
                .iter()
                .map(|s| {
                    let points: Vec<[f64; 2]> = s
                        .points
                        .iter()
                        .filter(|(t, e)| *t > 0.0 && *e > 0.0 && t.is_finite() && e.is_finite())
                        .map(|&(t, e)| [t, e])
                        .collect();
                    json!({ "name": s.name, "color": s.color, "points": points })
                })
                .collect();
            json!({ "title": c.title, "x_label": c.x_label, "y_label": c.y_label, "series": series })
        })
        .collect();
    let value = json!({
        "title": report.title,
        "reference": image_json("reference", "", &report.reference),
        "methods": report.methods.iter().map(|m| image_json(&m.name, &m.caption, &m.image)).collect::<Vec<_>>(),
        "charts": charts,
    });
    script_safe(&value.to_string())
}

/// JSON that cannot end its `<script>` element or open a comment there: `<`, `>` and `&` only
/// occur inside JSON strings, where `\u003c` and the like mean the same.
fn script_safe(json: &str) -> String {
    json.replace('<', "\\u003c").replace('>', "\\u003e").replace('&', "\\u0026")
}

/// Text for HTML content and attribute values.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: usize, height: usize, v: f32) -> HtmlImage {
        HtmlImage { width, height, rgb: (0..width * height * 3).map(|i| v + i as f32 * 0.01).collect() }
    }

    fn report(names: &[&str]) -> HtmlReport {
        HtmlReport {
            title: "compare <scene> & \"more\"".into(),
            notes: vec!["a note with <tags> & \"quotes\"".into(), "second".into()],
            reference: image(4, 3, 0.5),
            methods: names
                .iter()
                .enumerate()
                .map(|(i, n)| HtmlMethod {
                    name: n.to_string(),
                    caption: format!("caption of {n}"),
                    image: image(4, 3, i as f32),
                })
                .collect(),
            charts: vec![HtmlChart {
                title: "relMSE vs time".into(),
                x_label: "seconds".into(),
                y_label: "relMSE".into(),
                series: names
                    .iter()
                    .map(|n| HtmlSeries {
                        name: n.to_string(),
                        color: "#1f77b4".into(),
                        points: vec![(0.5, 0.1), (1.0, 0.05), (0.0, 1.0), (2.0, f64::NAN)],
                    })
                    .collect(),
            }],
            table: HtmlTable {
                headers: vec!["integrator".into(), "relMSE".into()],
                rows: names.iter().map(|n| vec![n.to_string(), "1e-3".into()]).collect(),
            },
        }
    }

    /// The JSON data block of a page.
    fn data(page: &str) -> Value {
        let open = "<script type=\"application/json\" id=\"nimbus-data\">";
        let start = page.find(open).expect("a data block") + open.len();
        let end = start + page[start..].find("</script>").expect("its end");
        serde_json::from_str(&page[start..end]).expect("valid JSON")
    }

    fn unbase64(s: &str) -> Vec<u8> {
        const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let digits: Vec<u32> =
            s.bytes().filter(|&b| b != b'=').map(|b| ALPHABET.iter().position(|&a| a == b).unwrap() as u32).collect();
        let mut out = Vec::new();
        for chunk in digits.chunks(4) {
            let n = chunk.iter().enumerate().fold(0u32, |n, (i, d)| n | d << (18 - 6 * i));
            out.extend([(n >> 16) as u8, (n >> 8) as u8, n as u8].iter().take(chunk.len() - 1));
        }
        out
    }

    #[test]
    fn base64_matches_the_standard_alphabet_and_padding() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
        assert_eq!(base64(&[0xff, 0xfe, 0x00, 0x80]), "//4AgA==");
        let bytes: Vec<u8> = (0..=255).collect();
        assert_eq!(unbase64(&base64(&bytes)), bytes);
    }

    #[test]
    fn the_page_fetches_nothing() {
        let page = page(&report(&["volpath", "simplevolpath"])).unwrap();
        for needle in ["http://", "https://", "src=", "href=", "url(", "@import", "//cdn"] {
            assert!(!page.to_lowercase().contains(needle), "the page contains {needle:?}");
        }
        assert!(page.starts_with("<!DOCTYPE html>"));
    }

    #[test]
    fn every_image_is_embedded_once_as_little_endian_float32() {
        let r = report(&["volpath", "simplevolpath", "pathgraph"]);
        let d = data(&page(&r).unwrap());
        let methods = d["methods"].as_array().unwrap();
        assert_eq!(methods.len(), 3);
        let embedded: Vec<&Value> = std::iter::once(&d["reference"]).chain(methods).collect();
        let originals: Vec<&HtmlImage> =
            std::iter::once(&r.reference).chain(r.methods.iter().map(|m| &m.image)).collect();
        assert_eq!(embedded.len(), 1 + r.methods.len());
        for (e, o) in embedded.iter().zip(originals) {
            assert_eq!((e["width"].as_u64(), e["height"].as_u64()), (Some(4), Some(3)));
            let bytes = unbase64(e["rgb"].as_str().unwrap());
            let floats: Vec<f32> = bytes.chunks(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
            assert_eq!(floats, o.rgb);
        }
        // The chart keeps only the points a log-log axis can show.
        assert_eq!(d["charts"][0]["series"][0]["points"], json!([[0.5, 0.1], [1.0, 0.05]]));
    }

    #[test]
    fn names_and_text_are_escaped() {
        let nasty = "<b>\"x\"</b>";
        let r = report(&[nasty, "</script><script>alert(1)</script>"]);
        let page = page(&r).unwrap();
        assert!(!page.contains(nasty), "the raw name is in the page");
        assert!(!page.contains("<script>alert"), "a name closed the data block");
        assert!(page.contains("<td>&lt;b&gt;&quot;x&quot;&lt;/b&gt;</td>"));
        assert!(page.contains("<title>compare &lt;scene&gt; &amp; &quot;more&quot;</title>"));
        assert!(page.contains("<p>a note with &lt;tags&gt; &amp; &quot;quotes&quot;</p>"));
        // The script reads the names back exactly.
        let d = data(&page);
        assert_eq!(d["methods"][0]["name"], nasty);
        assert_eq!(d["methods"][1]["name"], "</script><script>alert(1)</script>");
        assert_eq!(d["charts"][0]["series"][0]["name"], nasty);
        // Exactly the page's own script elements: the trap, the data and the script.
        assert_eq!(page.matches("<script").count(), 3);
    }

    #[test]
    fn the_assets_cannot_end_their_elements() {
        assert!(!SCRIPT.to_lowercase().contains("</script"));
        assert!(!STYLE.to_lowercase().contains("</style"));
        assert!(!ERROR_TRAP.contains('<'));
    }

    #[test]
    fn a_method_of_another_size_is_an_error_naming_it() {
        let mut r = report(&["volpath", "bad <one>"]);
        r.methods[1].image = image(5, 3, 0.0);
        let e = page(&r).unwrap_err().to_string();
        assert!(e.contains("method \"bad <one>\"") && e.contains("5×3") && e.contains("4×3"), "{e}");

        let mut r = report(&["short"]);
        r.methods[0].image.rgb.pop();
        let e = page(&r).unwrap_err().to_string();
        assert!(e.contains("method \"short\"") && e.contains("35 floats"), "{e}");

        let mut r = report(&["volpath"]);
        r.reference = image(0, 0, 0.0);
        assert!(page(&r).unwrap_err().to_string().contains("reference image is empty"));

        let dir = std::env::temp_dir().join(format!("nimbus-html-{}", std::process::id()));
        let path = dir.join("missing-folder").join("report.html");
        let e = write(&report(&["volpath"]), &path).unwrap_err();
        assert!(format!("{e:#}").contains("report.html"), "{e:#}");
    }

    #[test]
    fn write_writes_the_page() {
        let path = std::env::temp_dir().join(format!("nimbus-html-test-{}.html", std::process::id()));
        write(&report(&["volpath"]), &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert!(text.contains("data-chart=\"0\"") && text.contains("id=\"flip\""));
    }
}
