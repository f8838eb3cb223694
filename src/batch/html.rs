//! `OUT/report.html`: one self-contained page (no network, no scripts): the
//! run's counts, the summary pictures embedded as base64 data URIs, and the
//! summary table, with error rows marked and links to each shot's own plot.

use super::base64;
use super::plots::fmt_fnumber;
use super::record::ShotRecord;
use std::fmt::Write;

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
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

/// Escapes a relative file path for use in an `href` (percent-encoding
/// what a URL path cannot hold), keeping `/` separators.
fn href(path: &str) -> String {
    let mut out = String::new();
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"-_.~/".contains(&b) {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

fn num(v: Option<f64>, digits: usize) -> String {
    v.filter(|x| x.is_finite())
        .map(|x| format!("{x:.digits$}"))
        .unwrap_or_default()
}

fn exposure(v: Option<f64>) -> String {
    match v.filter(|x| x.is_finite() && *x > 0.0) {
        Some(t) if t < 0.5 => format!("1/{:.0} s", 1.0 / t),
        Some(t) => format!("{t} s"),
        None => String::new(),
    }
}

/// A picture to embed: caption and PNG bytes.
pub struct Picture<'a> {
    /// Caption shown under the picture.
    pub caption: &'a str,
    /// PNG file contents.
    pub png: &'a [u8],
}

/// Builds the report page for `records`; `shots_dir` is the per-shot folder
/// name relative to the page (for links to each shot's plot).
pub fn report_html(
    title: &str,
    records: &[ShotRecord],
    pictures: &[Picture<'_>],
    shots_dir: &str,
) -> String {
    let ok = records.iter().filter(|r| r.is_ok()).count();
    let failed = records.len() - ok;
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
<title>{t}</title>\n<style>\n\
body{{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:24px;color:#222;}}\n\
h1{{font-size:22px;margin:0 0 6px 0;}} p.meta{{color:#555;margin:0 0 16px 0;}}\n\
.pics{{display:flex;flex-wrap:wrap;gap:16px;margin-bottom:20px;}}\n\
figure{{margin:0;}} figure img{{max-width:100%;width:560px;border:1px solid #ddd;}}\n\
figcaption{{font-size:13px;color:#555;}}\n\
table{{border-collapse:collapse;font-size:13px;}}\n\
th,td{{border:1px solid #ddd;padding:3px 6px;text-align:right;white-space:nowrap;}}\n\
th{{background:#f2f2f2;position:sticky;top:0;}}\n\
td.l,th.l{{text-align:left;}} tr.err td{{background:#fdecea;}}\n\
td.e{{text-align:left;white-space:normal;color:#a00;min-width:320px;}}\n\
td.w{{text-align:left;white-space:normal;color:#777;font-size:12px;min-width:320px;}}\n\
.bad{{color:#a00;font-weight:bold;}}\n\
</style>\n</head>\n<body>\n<h1>{t}</h1>\n<p class=\"meta\">{n} shot{s}: {ok} measured, <span class=\"{cls}\">{failed} failed</span>.</p>\n",
        t = escape(title),
        n = records.len(),
        s = if records.len() == 1 { "" } else { "s" },
        cls = if failed > 0 { "bad" } else { "" },
    );
    if !pictures.is_empty() {
        h.push_str("<div class=\"pics\">\n");
        for p in pictures {
            let _ = writeln!(
                h,
                "<figure><img alt=\"{c}\" src=\"data:image/png;base64,{d}\"><figcaption>{c}</figcaption></figure>",
                c = escape(p.caption),
                d = base64::encode(p.png)
            );
        }
        h.push_str("</div>\n");
    }
    h.push_str(
        "<table>\n<thead><tr><th>#</th><th class=\"l\">file</th><th class=\"l\">status</th>\
<th>MTF50<br>cy/px</th><th>MTF50<br>cy/mm</th><th>MTF50<br>LW/PH</th><th>MTF20<br>cy/px</th><th>MTF10<br>cy/px</th>\
<th>MTF50P<br>cy/px</th><th>MTF20P<br>cy/px</th><th>MTF10P<br>cy/px</th><th>peak<br>MTF</th><th>peak at<br>cy/px</th>\
<th>MTF at<br>Nyquist</th><th class=\"l\">method</th><th>f-number</th><th>focal<br>length</th><th>ISO</th>\
<th>exposure</th><th class=\"l\">camera</th><th class=\"l\">lens</th><th>time<br>s</th><th class=\"l\">error / warnings</th></tr></thead>\n<tbody>\n",
    );
    for (i, r) in records.iter().enumerate() {
        let x = &r.result;
        let plot = x
            .outputs
            .iter()
            .find(|o| o.ends_with(".mtf.png") || o.ends_with(".mtf.svg"));
        let file = match plot {
            Some(p) => format!(
                "<a href=\"{}\">{}</a>",
                href(&format!("{shots_dir}/{p}")),
                escape(&r.file)
            ),
            None => escape(&r.file),
        };
        let camera = [x.make.as_deref(), x.model.as_deref()]
            .iter()
            .flatten()
            .copied()
            .collect::<Vec<_>>()
            .join(" ");
        let note = match &r.error {
            Some(e) => e.clone(),
            None => x.warnings.join("; "),
        };
        let _ = writeln!(
            h,
            "<tr{cls}><td>{n}</td><td class=\"l\">{file}</td><td class=\"l\">{st}</td>\
<td>{m50}</td><td>{m50mm}</td><td>{m50lw}</td><td>{m20}</td><td>{m10}</td>\
<td>{m50p}</td><td>{m20p}</td><td>{m10p}</td><td>{pk}</td><td>{pkf}</td><td>{nyq}</td><td class=\"l\">{method}</td>\
<td>{fnum}</td><td>{fl}</td><td>{iso}</td><td>{exp}</td><td class=\"l\">{cam}</td><td class=\"l\">{lens}</td>\
<td>{rt:.2}</td><td class=\"{ncls}\">{note}</td></tr>",
            cls = if r.is_ok() { "" } else { " class=\"err\"" },
            n = i + 1,
            st = r.status.as_str(),
            m50 = num(x.mtf50_cy_px, 4),
            m50mm = num(x.mtf50_cy_mm, 1),
            m50lw = num(x.mtf50_lw_ph, 0),
            m20 = num(x.mtf20_cy_px, 4),
            m10 = num(x.mtf10_cy_px, 4),
            m50p = num(x.mtf50p_cy_px, 4),
            m20p = num(x.mtf20p_cy_px, 4),
            m10p = num(x.mtf10p_cy_px, 4),
            pk = num(x.mtf_peak, 3),
            pkf = num(x.mtf_peak_cy_px, 4),
            nyq = num(x.mtf_nyquist, 3),
            method = escape(x.method.as_deref().unwrap_or("")),
            fnum = x
                .f_number
                .map(|n| format!("f/{}", fmt_fnumber(n)))
                .unwrap_or_default(),
            fl = x
                .focal_length_mm
                .map(|f| format!("{f} mm"))
                .unwrap_or_default(),
            iso = num(x.iso, 0),
            exp = exposure(x.exposure_time_s),
            cam = escape(&camera),
            lens = escape(x.lens.as_deref().unwrap_or("")),
            rt = r.run_time_s,
            ncls = if r.is_ok() { "w" } else { "e" },
            note = escape(&note),
        );
    }
    h.push_str("</tbody>\n</table>\n</body>\n</html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_urls() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
        assert_eq!(href("shots/a b#.png"), "shots/a%20b%23.png");
    }

    #[test]
    fn exposure_is_written_as_a_fraction() {
        assert_eq!(exposure(Some(0.004)), "1/250 s");
        assert_eq!(exposure(Some(2.0)), "2 s");
    }
}
