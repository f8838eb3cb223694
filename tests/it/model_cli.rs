//! `sweepmtf model` end to end: the three output modes, their files and
//! columns, values against closed forms computed here, the shipped example
//! systems, and the bad-input contract (one line naming the parameter, exit 2;
//! earlier outputs never clobbered).

use assert_cmd::Command;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn cmd() -> Command {
    Command::cargo_bin("sweepmtf").unwrap()
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn read_csv(p: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}

/// Runs the model with `args` and returns (exit code, stderr).
fn fails(args: &[&str]) -> (i32, String) {
    let out = cmd().arg("model").args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn at_points_gives_one_row_per_point_in_order_with_factor_columns() {
    let dir = tempfile::tempdir().unwrap();
    let pts = dir.path().join("p.csv");
    // λ·F# = 2⁻⁹ mm: cutoff 512 cycles/mm.
    std::fs::write(
        &pts,
        "u_cy_mm,v_cy_mm\n0,0\n256,0\n0,-256\n300,400\n511.9999999999,0\n1e300,5e-324\n-7.5,3\n400,-400\n",
    )
    .unwrap();
    let out = dir.path().join("o.csv");
    cmd()
        .args([
            "model",
            "--optics",
            "diffraction:lambda=0.48828125um,fnum=4",
        ])
        .args(["--gaussian", "sigma=1um", "--at"])
        .arg(&pts)
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let (h, rows) = read_csv(&out);
    assert_eq!(
        h,
        [
            "u_cy_mm",
            "v_cy_mm",
            "otf_re",
            "otf_im",
            "mtf",
            "mtf_diffraction",
            "mtf_gaussian"
        ]
    );
    assert_eq!(rows.len(), 8);
    assert_eq!((rows[3][0], rows[3][1]), (300.0, 400.0));
    assert_eq!((rows[6][0], rows[6][1]), (-7.5, 3.0));
    let eq44 = |s: f64| 2.0 / PI * (s.acos() - s * (1.0 - s * s).sqrt());
    let gauss = |rho: f64| (-2.0 * PI * PI * (1e-3 * rho).powi(2)).exp();
    for (i, rho) in [(0, 0.0), (1, 256.0), (2, 256.0), (3, 500.0)] {
        let want_d = if rho < 512.0 { eq44(rho / 512.0) } else { 0.0 };
        assert!((rows[i][5] - want_d).abs() < 1e-15, "row {i}");
        assert!((rows[i][6] - gauss(rho)).abs() < 1e-15, "row {i}");
        assert!((rows[i][4] - want_d * gauss(rho)).abs() < 1e-15, "row {i}");
        assert_eq!(rows[i][3], 0.0);
    }
    // Past the cutoff: exactly zero; just inside: tiny but positive.
    assert_eq!(rows[7][5], 0.0);
    assert!(rows[4][5] > 0.0 && rows[4][5] < 1e-17, "{}", rows[4][5]);
    assert_eq!(rows[5][4], 0.0);
    // Full precision: the printed values round-trip to the computed f64.
    let text = std::fs::read_to_string(&out).unwrap();
    let line = text.lines().nth(2).unwrap();
    let mtf: f64 = line.split(',').nth(5).unwrap().parse().unwrap();
    assert_eq!(format!("{mtf}"), line.split(',').nth(5).unwrap());
}

#[test]
fn cut_writes_csv_and_plot_with_the_readme_system() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sub/cut.csv");
    cmd()
        .args(["model", "--system"])
        .arg(repo("targets/systems/aps_c_f4.toml"))
        .args(["--cut", "u", "--f-max", "300", "--points", "301", "-o"])
        .arg(&out)
        .assert()
        .success();
    let (h, rows) = read_csv(&out);
    assert_eq!(
        &h[..6],
        [
            "freq_cy_mm",
            "u_cy_mm",
            "v_cy_mm",
            "otf_re",
            "otf_im",
            "mtf"
        ]
    );
    assert_eq!(h.len(), 9);
    assert_eq!(rows.len(), 301);
    assert_eq!(rows[0][5], 1.0);
    assert_eq!(rows[300][0], 300.0);
    // 4.3 µm rect aperture × 4.3 µm rect sampling × f/4 at 550 nm, at 100 cy/mm.
    let r = &rows[100];
    let sinc = |x: f64| (PI * x).sin() / (PI * x);
    let s = 100.0 * 550e-6 * 4.0;
    let want = 2.0 / PI * (f64::acos(s) - s * (1.0 - s * s).sqrt()) * sinc(0.43).powi(2);
    assert!((r[5] - want).abs() < 1e-13, "{} vs {want}", r[5]);
    let png = image::open(out.with_extension("png")).unwrap();
    assert_eq!((png.width(), png.height()), (1000, 640));
}

#[test]
fn cut_at_an_angle_and_svg_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.csv");
    let svg = dir.path().join("c.svg");
    cmd()
        .args(["model", "--gaussian", "sigma_x=2um,sigma_y=1um"])
        .args([
            "--cut", "deg=90", "--f-max", "100", "--points", "11", "--plot",
        ])
        .arg(&svg)
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let (_, rows) = read_csv(&out);
    for r in &rows {
        assert_eq!(r[1], 0.0);
        let want = (-2.0 * PI * PI * (1e-3 * r[2]).powi(2)).exp();
        assert!((r[5] - want).abs() < 1e-15);
    }
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
}

#[test]
fn map_writes_a_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.png");
    cmd()
        .args(["model", "--system"])
        .arg(repo("targets/systems/hex_sensor.toml"))
        .args(["--map", "--f-max", "250", "--size", "128", "-o"])
        .arg(&out)
        .assert()
        .success();
    let img = image::open(&out).unwrap();
    assert!(img.width() > 128 && img.height() > 128);
}

#[test]
fn every_shipped_system_builds_and_is_one_at_the_origin() {
    let mut n = 0;
    for e in std::fs::read_dir(repo("targets/systems")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let s = sweepmtf::model::System::from_file(&p)
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert!(!s.factors.is_empty());
            assert!((s.mtf(0.0, 0.0) - 1.0).abs() < 1e-15, "{}", p.display());
            n += 1;
        }
    }
    assert!(n >= 4);
}

#[test]
fn bad_input_is_one_line_naming_the_parameter_with_exit_code_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.csv");
    let o = out.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--optics", "diffraction:lambda=550nm,fnum=0"], "fnum"),
        (&["--optics", "diffraction:lambda=550nm,fnum=-2"], "fnum"),
        (&["--optics", "diffraction:lambda=-550nm,fnum=4"], "lambda"),
        (&["--optics", "diffraction:lambda=0nm,fnum=4"], "lambda"),
        (&["--optics", "diffraction:lambda=550,fnum=4"], "lambda"),
        (
            &["--optics", "diffraction:lambda=550nm,fnum=4,zoom=2"],
            "zoom",
        ),
        (&["--optics", "pinhole:d=1um"], "pinhole"),
        (&["--cte", "n=10,cti=1.5,pitch=5um"], "cti"),
        (&["--cte", "n=10,cti=-0.1,pitch=5um"], "cti"),
        (&["--cte", "n=10,cte=2,pitch=5um"], "cte"),
        (&["--cte", "n=10.5,cti=0.1,pitch=5um"], "n must"),
        (&["--cte", "n=10,cti=0.1,pitch=0um"], "pitch"),
        (&["--gaussian", "sigma=5"], "sigma"),
        (&["--gaussian", "sigma=0um"], "sigma"),
        (&["--olpf", "2spot:d=-1um"], "d"),
        (&["--olpf", "3spot:d=1um"], "3spot"),
        (
            &["--diffusion", "alpha=0.05,depletion=1um,length=5um"],
            "alpha",
        ),
        (
            &["--diffusion", "lambda=2000nm,depletion=1um,length=5um"],
            "lambda",
        ),
        (
            &["--diffusion", "alpha=0.05/um,depletion=-1um,length=5um"],
            "depletion",
        ),
        (
            &["--diffusion", "alpha=0.05/um,depletion=1um,length=0um"],
            "length",
        ),
        (&["--defocus", "wave:lambda=550nm,fnum=4"], "w020"),
        (&["--defocus", "geometric:blur=0um"], "blur"),
        (&["--aperture", "rect:A=0um,B=1um"], "A"),
    ];
    for (args, needle) in cases {
        let (code, err) = fails(&[args, &["--cut", "u", "--f-max", "100", "-o", o][..]].concat());
        assert_eq!(code, 2, "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: '{err}' lacks '{needle}'");
        assert!(!out.exists(), "{args:?} wrote output");
    }
}

#[test]
fn usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.csv");
    let o = out.to_str().unwrap();
    // No factor.
    let (code, err) = fails(&["--cut", "u", "--f-max", "100", "-o", o]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no model factor"), "{err}");
    // No mode, two modes, missing --f-max, bad direction.
    let g = ["--gaussian", "sigma=1um"];
    for extra in [
        &["-o", o][..],
        &["--cut", "u", "-o", o],
        &["--cut", "w", "--f-max", "1", "-o", o],
        &["--cut", "u", "--map", "--f-max", "1", "-o", o],
        &["--cut", "u", "--f-max", "-1", "-o", o],
        &["--map", "--f-max", "1", "-o", "x.csv"],
    ] {
        let (code, err) = fails(&[&g[..], extra].concat());
        assert_eq!(code, 2, "{extra:?}: {err}");
    }
    // System file with an unknown key: 2; missing system file: 3.
    let sys = dir.path().join("s.toml");
    std::fs::write(&sys, "name = \"x\"\ncolour = 1\n").unwrap();
    let (code, err) = fails(&[
        "--system",
        sys.to_str().unwrap(),
        "--cut",
        "u",
        "--f-max",
        "1",
        "-o",
        o,
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("colour") && err.contains("s.toml"), "{err}");
    let (code, err) = fails(&[
        "--system",
        "/nonexistent/s.toml",
        "--cut",
        "u",
        "--f-max",
        "1",
        "-o",
        o,
    ]);
    assert_eq!(code, 3, "{err}");
    // Points file without the right header, or with a bad number: 3.
    let pts = dir.path().join("p.csv");
    std::fs::write(&pts, "u,v\n1,2\n").unwrap();
    let (code, err) = fails(&[&g[..], &["--at", pts.to_str().unwrap(), "-o", o]].concat());
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("u_cy_mm"), "{err}");
    std::fs::write(&pts, "u_cy_mm,v_cy_mm\n1,2\n3,nan\n").unwrap();
    let (code, err) = fails(&[&g[..], &["--at", pts.to_str().unwrap(), "-o", o]].concat());
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("line 3"), "{err}");
}

#[test]
fn failures_never_clobber_earlier_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.csv");
    std::fs::write(&out, "earlier result\n").unwrap();
    let (code, _) = fails(&[
        "--gaussian",
        "sigma=-1um",
        "--cut",
        "u",
        "--f-max",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "earlier result\n");
    // An output whose folder cannot be created: exit 6, one line.
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, "x").unwrap();
    let bad = blocker.join("o.csv");
    let (code, err) = fails(&[
        "--gaussian",
        "sigma=1um",
        "--cut",
        "u",
        "--f-max",
        "1",
        "-o",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(code, 6, "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}
