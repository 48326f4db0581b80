//! Unit tests of the field files: every dataset, attribute and XDMF element, names, atomicity.

use super::*;

/// Structured mesh of [0,1]² with n×n squares, two triangles each (same as check_meshio.py).
fn square_mesh(key: &str, n: usize) -> MeshData {
    let mut points = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            points.push([i as f64 / n as f64, j as f64 / n as f64]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            triangles.push([a, a + 1, a + n + 2]);
            triangles.push([a, a + n + 2, a + n + 1]);
        }
    }
    MeshData {
        key: key.to_string(),
        points,
        triangles,
    }
}

/// u = s(x + 2y), p = s(xy, x − y), crack on y = 1/2 from x = 1/4 to 3/4 with `ni` segments,
/// lambda = s·k per node or s·(k + 1/2) per segment, and with it jump = s·(ni − k) per node;
/// metadata δ = `delta`, level = `ni − 1`.
#[allow(clippy::too_many_arguments)]
fn case(
    name: &str,
    series: &str,
    delta: f64,
    mesh: &MeshData,
    s: f64,
    ni: usize,
    p: bool,
    lambda: Option<Centering>,
) -> CaseFields {
    let crack_points: Vec<[f64; 2]> = (0..=ni)
        .map(|k| [0.25 + 0.5 * k as f64 / ni as f64, 0.5])
        .collect();
    CaseFields {
        name: name.to_string(),
        mesh_key: mesh.key.clone(),
        u: Some(
            mesh.points
                .iter()
                .map(|q| s * (q[0] + 2.0 * q[1]))
                .collect(),
        ),
        p: p.then(|| {
            mesh.points
                .iter()
                .map(|q| [s * q[0] * q[1], s * (q[0] - q[1])])
                .collect()
        }),
        p_bubble: p.then(|| {
            (0..mesh.triangles.len())
                .map(|t| [s * t as f64, -s])
                .collect()
        }),
        crack_points,
        crack_segments: (0..ni).map(|k| [k, k + 1]).collect(),
        lambda: lambda.map(|c| match c {
            Centering::Node => (c, (0..=ni).map(|k| s * k as f64).collect()),
            Centering::Cell => (c, (0..ni).map(|k| s * (k as f64 + 0.5)).collect()),
        }),
        jump: lambda.map(|_| (0..=ni).map(|k| s * (ni - k) as f64).collect()),
        series: series.to_string(),
        metadata: vec![
            ("level".into(), Meta::Int(ni as i64 - 1)),
            ("u_space".into(), Meta::Text("P1".into())),
            ("delta".into(), Meta::Float(delta)),
        ],
        constants: vec![("delta".into(), delta)],
        extra: vec![],
    }
}

const ODD: &str = "odd <&>\"' name";

/// The fixture that test_xdmf_readback.py expects: three series, the first with two steps.
fn fixture() -> (Vec<MeshData>, Vec<CaseFields>) {
    let m2 = square_mesh("level1-P1", 2);
    let m4 = square_mesh("level2-P1", 4);
    let unused = square_mesh("unused", 1);
    let (s1, s2) = ("level1-P1-P0", "level2-P1-P1");
    let cell = Some(Centering::Cell);
    let cases = vec![
        case("level1-P1-P0-delta1e-2", s1, 1e-2, &m2, 1.0, 2, true, cell),
        case(
            "level2-P1-P1-delta1.5e-2",
            s2,
            1.5e-2,
            &m4,
            2.0,
            4,
            true,
            Some(Centering::Node),
        ),
        case("level1-P1-P0-delta0", s1, 0.0, &m2, 4.0, 2, true, cell),
        case(ODD, ODD, 0.0, &m2, 3.0, 2, false, None),
    ];
    (vec![m2, m4, unused], cases)
}

fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = vec![(
        "fields.h5".to_string(),
        fs::read(dir.join("fields.h5")).unwrap(),
    )];
    for name in listing(&dir.join("fields")) {
        let bytes = fs::read(dir.join("fields").join(&name)).unwrap();
        out.push((format!("fields/{name}"), bytes));
    }
    out
}

/// Writes the fixture; into $SDCRACK_FIELDS_DIR when set, for the Python read-back check.
#[test]
fn fixture_for_python_and_h5_readback() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = match std::env::var_os("SDCRACK_FIELDS_DIR") {
        Some(d) => {
            let d = PathBuf::from(d);
            fs::create_dir_all(&d).unwrap();
            d
        }
        None => tmp.path().to_path_buf(),
    };
    let (meshes, cases) = fixture();
    write_fields(&dir, "fields", &meshes, &cases).unwrap();

    let f = hdf5::File::open(dir.join("fields.h5")).unwrap();
    let mut mesh_names = f.group("meshes").unwrap().member_names().unwrap();
    mesh_names.sort();
    assert_eq!(
        mesh_names,
        ["level1-P1", "level2-P1"],
        "only used meshes, once each"
    );
    for m in &meshes[..2] {
        let pts = f.dataset(&format!("meshes/{}/points", m.key)).unwrap();
        assert_eq!(pts.shape(), [m.points.len(), 3]);
        assert_eq!(pts.read_raw::<f64>().unwrap(), pad3(&m.points));
        let tri = f.dataset(&format!("meshes/{}/triangles", m.key)).unwrap();
        assert_eq!(tri.shape(), [m.triangles.len(), 3]);
        let want: Vec<i64> = m.triangles.iter().flatten().map(|&i| i as i64).collect();
        assert_eq!(tri.read_raw::<i64>().unwrap(), want);
    }
    for c in &cases {
        let g = f.group(&format!("cases/{}", c.name)).unwrap();
        let n = meshes
            .iter()
            .find(|m| m.key == c.mesh_key)
            .unwrap()
            .points
            .len();
        // soft link resolves to the shared mesh
        assert_eq!(g.dataset("mesh/points").unwrap().shape(), [n, 3]);
        match &c.u {
            Some(u) => {
                let ds = g.dataset("u").unwrap();
                assert_eq!(ds.shape(), [n]);
                assert_eq!(&ds.read_raw::<f64>().unwrap(), u);
            }
            None => assert!(!g.link_exists("u")),
        }
        match &c.p {
            Some(p) => {
                let ds = g.dataset("p").unwrap();
                assert_eq!(ds.shape(), [n, 3]);
                assert_eq!(ds.read_raw::<f64>().unwrap(), pad3(p));
            }
            None => assert!(!g.link_exists("p")),
        }
        let ni = c.crack_points.len() - 1;
        let pts = g.dataset("crack/points").unwrap();
        assert_eq!(pts.shape(), [ni + 1, 3]);
        assert_eq!(pts.read_raw::<f64>().unwrap(), pad3(&c.crack_points));
        let seg = g.dataset("crack/segments").unwrap();
        assert_eq!(seg.shape(), [ni, 2]);
        let want: Vec<i64> = (0..ni as i64).flat_map(|k| [k, k + 1]).collect();
        assert_eq!(seg.read_raw::<i64>().unwrap(), want);
        match &c.lambda {
            Some((_, l)) => {
                let ds = g.dataset("crack/lambda").unwrap();
                assert_eq!(ds.shape(), [l.len()]);
                assert_eq!(&ds.read_raw::<f64>().unwrap(), l);
            }
            None => assert!(!g.link_exists("crack/lambda")),
        }
        match &c.jump {
            Some(j) => {
                let ds = g.dataset("crack/jump").unwrap();
                assert_eq!(ds.shape(), [ni + 1]);
                assert_eq!(&ds.read_raw::<f64>().unwrap(), j);
            }
            None => assert!(!g.link_exists("crack/jump")),
        }
    }

    // Attributes on the case group and its field datasets.
    let g = f.group("cases/level1-P1-P0-delta0").unwrap();
    for loc in [
        g.dataset("u").unwrap().as_location().unwrap(),
        g.dataset("p").unwrap().as_location().unwrap(),
        g.dataset("crack/lambda").unwrap().as_location().unwrap(),
        g.dataset("crack/jump").unwrap().as_location().unwrap(),
        g.as_location().unwrap(),
    ] {
        assert_eq!(
            loc.attr("delta").unwrap().read_scalar::<f64>().unwrap(),
            0.0
        );
        assert_eq!(loc.attr("level").unwrap().read_scalar::<i64>().unwrap(), 1);
        assert_eq!(loc.attr("step").unwrap().read_scalar::<i64>().unwrap(), 1);
        let series: hdf5::types::VarLenUnicode = loc.attr("series").unwrap().read_scalar().unwrap();
        assert_eq!(series.as_str(), "level1-P1-P0");
    }
    drop(f);

    let xdmf = fs::read_to_string(dir.join("fields/level1-P1-P0.series.xdmf")).unwrap();
    assert!(xdmf.contains("<Xdmf Version=\"3.0\">"));
    assert!(xdmf.contains("CollectionType=\"Temporal\""));
    assert!(xdmf.contains(">../fields.h5:/meshes/level1-P1/points<"));
    assert!(
        !xdmf.contains(".tmp-"),
        "must reference the final file name"
    );
    let steps: Vec<&str> = xdmf.matches("<Time Value=").collect();
    assert_eq!(steps.len(), 2, "two δ steps");
    assert!(xdmf.find("<Time Value=\"0\"/>") < xdmf.find("<Time Value=\"1\"/>"));
    assert!(xdmf.contains("<Information Name=\"delta\" Value=\"1e-2\"/>"));
    assert!(xdmf.contains("<Information Name=\"delta\" Value=\"0\"/>"));
    let crack = fs::read_to_string(dir.join("fields/level1-P1-P0-delta0.crack.xdmf")).unwrap();
    assert!(crack.contains("<Attribute Name=\"jump\" AttributeType=\"Scalar\" Center=\"Node\">"));
    assert!(crack.contains(">../fields.h5:/cases/level1-P1-P0-delta0/crack/jump<"));
    let odd = fs::read_to_string(dir.join(format!("fields/{ODD}.crack.series.xdmf"))).unwrap();
    assert!(!odd.contains("jump"));
    assert!(odd.contains("Name=\"odd &lt;&amp;&gt;&quot;&apos; name/crack\""));
    // one state per case: a single grid, no Time, no Information, the same data items
    let state = fs::read_to_string(dir.join("fields/level1-P1-P0-delta0.xdmf")).unwrap();
    assert!(!state.contains("Collection") && !state.contains("<Time"));
    assert!(!state.contains("<Information"));
    assert_eq!(state.matches("<Grid ").count(), 1);
    assert!(state.contains(">../fields.h5:/cases/level1-P1-P0-delta0/u<"));
    let mut want_files = vec![];
    for series in ["level1-P1-P0", "level2-P1-P1", ODD] {
        want_files.push(format!("{series}.series.xdmf"));
        want_files.push(format!("{series}.crack.series.xdmf"));
    }
    for case in [
        "level1-P1-P0-delta1e-2",
        "level1-P1-P0-delta0",
        "level2-P1-P1-delta1.5e-2",
        ODD,
    ] {
        want_files.push(format!("{case}.xdmf"));
        want_files.push(format!("{case}.crack.xdmf"));
    }
    want_files.sort();
    assert_eq!(listing(&dir.join("fields")), want_files);
    assert!(!listing(&dir).iter().any(|n| n.starts_with('.')));
}

/// Every dataset of an HDF5 file (recursively, soft links skipped) with its values as bits
/// and its attributes as text.
fn h5_contents(path: &Path) -> Vec<(String, Vec<u64>, Vec<String>)> {
    fn walk(g: &hdf5::Group, prefix: &str, out: &mut Vec<(String, Vec<u64>, Vec<String>)>) {
        let attrs = |loc: &hdf5::Location| -> Vec<String> {
            let mut names = loc.attr_names().unwrap();
            names.sort();
            names
                .into_iter()
                .map(|n| {
                    let a = loc.attr(&n).unwrap();
                    let v = a
                        .read_scalar::<f64>()
                        .map(|x| x.to_bits().to_string())
                        .or_else(|_| {
                            a.read_scalar::<hdf5::types::VarLenUnicode>()
                                .map(|t| t.to_string())
                        })
                        .unwrap();
                    format!("{n}={v}")
                })
                .collect()
        };
        for name in g.member_names().unwrap() {
            let path = format!("{prefix}/{name}");
            if name == "mesh" {
                continue; // the soft link to /meshes/KEY
            }
            if let Ok(sub) = g.group(&name) {
                out.push((path.clone(), vec![], attrs(&sub)));
                walk(&sub, &path, out);
            } else {
                let ds = g.dataset(&name).unwrap();
                let bits = ds
                    .read_raw::<f64>()
                    .unwrap()
                    .iter()
                    .map(|v| v.to_bits())
                    .collect();
                out.push((path, bits, attrs(&ds)));
            }
        }
    }
    let f = hdf5::File::open(path).unwrap();
    let mut out = Vec::new();
    walk(&f, "", &mut out);
    out.sort();
    out
}

/// The HDF5 part alone: the same datasets, values and attributes as with the series, no
/// series folder (an existing one is left alone), and the same validation.
#[test]
fn h5_only_writes_the_same_heavy_file_and_no_series() {
    let tmp = tempfile::tempdir().unwrap();
    let (meshes, cases) = fixture();
    let full = tmp.path().join("full");
    let alone = tmp.path().join("alone");
    fs::create_dir(&full).unwrap();
    fs::create_dir(&alone).unwrap();
    write_fields(&full, "fields", &meshes, &cases).unwrap();
    write_h5_only(&alone, "verification", &meshes, &cases).unwrap();
    assert_eq!(listing(&alone), ["verification.h5"]);
    let want = h5_contents(&full.join("fields.h5"));
    assert!(want.len() > 20, "{}", want.len());
    assert_eq!(h5_contents(&alone.join("verification.h5")), want);
    // the soft link of a case still resolves
    let f = hdf5::File::open(alone.join("verification.h5")).unwrap();
    let pts = f.dataset("cases/level1-P1-P0-delta0/mesh/points").unwrap();
    assert_eq!(pts.shape(), [9, 3]);
    drop(f);

    // an unrelated folder of the stem's name is neither needed nor touched
    fs::create_dir(alone.join("verification")).unwrap();
    fs::write(alone.join("verification/keep"), b"k").unwrap();
    let (m, mut c) = fixture();
    c.truncate(1);
    write_h5_only(&alone, "verification", &m, &c).unwrap();
    assert_eq!(listing(&alone), ["verification", "verification.h5"]);
    assert_eq!(listing(&alone.join("verification")), ["keep"]);
    let f = hdf5::File::open(alone.join("verification.h5")).unwrap();
    assert_eq!(f.group("cases").unwrap().member_names().unwrap().len(), 1);
    drop(f);

    // invalid input: an error naming the case, nothing written, the old file kept
    let before = fs::read(alone.join("verification.h5")).unwrap();
    let mut bad = cases.clone();
    bad[0].u.as_mut().unwrap().pop();
    let e = write_h5_only(&alone, "verification", &meshes, &bad).unwrap_err();
    assert!(matches!(e, OutputError::Invalid(_)), "{e}");
    assert!(e.to_string().contains("field u"), "{e}");
    assert_eq!(fs::read(alone.join("verification.h5")).unwrap(), before);
    assert_eq!(listing(&alone), ["verification", "verification.h5"]);
}

#[test]
fn nonexistent_dir_is_an_error_without_leftovers() {
    let tmp = tempfile::tempdir().unwrap();
    let (meshes, cases) = fixture();
    let missing = tmp.path().join("missing");
    let e = write_fields(&missing, "fields", &meshes, &cases).unwrap_err();
    assert!(matches!(e, OutputError::Io { .. }), "{e}");
    assert!(listing(tmp.path()).is_empty());
}

#[test]
fn read_only_dir_is_an_error_without_leftovers() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().unwrap();
    let ro = tmp.path().join("ro");
    fs::create_dir(&ro).unwrap();
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).unwrap();
    if fs::File::create(ro.join("probe")).is_ok() {
        // Running as root (or on a file system ignoring modes): cannot test this here.
        eprintln!("skipped: read-only permission is not enforced for this user");
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).unwrap();
        return;
    }
    let (meshes, cases) = fixture();
    let e = write_fields(&ro, "fields", &meshes, &cases).unwrap_err();
    assert!(matches!(e, OutputError::Io { .. }), "{e}");
    assert!(listing(&ro).is_empty());
    fs::set_permissions(&ro, fs::Permissions::from_mode(0o755)).unwrap();
}

#[test]
fn unwritable_target_cleans_temporaries_and_keeps_old_files() {
    // Works as root too: the final h5 name is a non-empty directory, so the first rename
    // fails after all temporaries were written.
    let tmp = tempfile::tempdir().unwrap();
    let (meshes, cases) = fixture();
    fs::create_dir(tmp.path().join("fields.h5")).unwrap();
    fs::write(tmp.path().join("fields.h5/keep"), b"x").unwrap();
    fs::create_dir(tmp.path().join("fields")).unwrap();
    fs::write(tmp.path().join("fields/old.xdmf"), b"old").unwrap();
    let e = write_fields(tmp.path(), "fields", &meshes, &cases).unwrap_err();
    assert!(matches!(e, OutputError::Io { .. }), "{e}");
    assert_eq!(listing(tmp.path()), ["fields", "fields.h5"]);
    assert_eq!(
        fs::read(tmp.path().join("fields/old.xdmf")).unwrap(),
        b"old"
    );
}

#[test]
fn overwrite_replaces_both_and_per_case_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let (meshes, cases) = fixture();
    write_fields(tmp.path(), "fields", &meshes, &cases).unwrap();
    let before = snapshot(tmp.path());
    let (m, mut c) = fixture();
    c.truncate(1);
    c[0].u = Some(vec![7.0; m[0].points.len()]);
    write_fields(tmp.path(), "fields", &m, &c).unwrap();
    let after = snapshot(tmp.path());
    assert_ne!(before[0].1, after[0].1, "h5 replaced");
    assert_ne!(before[2].1, after[2].1, "xdmf replaced");
    assert_eq!(
        listing(&tmp.path().join("fields")),
        [
            "level1-P1-P0-delta1e-2.crack.xdmf",
            "level1-P1-P0-delta1e-2.xdmf",
            "level1-P1-P0.crack.series.xdmf",
            "level1-P1-P0.series.xdmf"
        ]
    );
    assert_eq!(listing(tmp.path()), ["fields", "fields.h5"]);
    let f = hdf5::File::open(tmp.path().join("fields.h5")).unwrap();
    let u = f.dataset("cases/level1-P1-P0-delta1e-2/u").unwrap();
    assert_eq!(u.read_raw::<f64>().unwrap(), vec![7.0; 9]);
    assert_eq!(f.group("cases").unwrap().member_names().unwrap().len(), 1);
}

fn expect_invalid(meshes: &[MeshData], cases: &[CaseFields], needles: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let (m0, c0) = fixture();
    write_fields(tmp.path(), "fields", &m0, &c0).unwrap();
    let before = snapshot(tmp.path());
    let e = write_fields(tmp.path(), "fields", meshes, cases).unwrap_err();
    assert!(matches!(e, OutputError::Invalid(_)), "{e}");
    let msg = e.to_string();
    for n in needles {
        assert!(msg.contains(n), "{msg:?} lacks {n:?}");
    }
    assert_eq!(snapshot(tmp.path()), before, "old files byte-identical");
    assert_eq!(listing(tmp.path()), ["fields", "fields.h5"]);
}

#[test]
fn validation_failures_leave_old_files_untouched() {
    let (m, c) = fixture();
    let case0 = "level1-P1-P0-delta1e-2";

    let mut cc = c.clone();
    cc[0].mesh_key = "nope".into();
    expect_invalid(&m, &cc, &[case0, "nope"]);

    let mut cc = c.clone();
    cc[0].u.as_mut().unwrap().pop();
    expect_invalid(&m, &cc, &[case0, "field u", "8 values"]);

    let mut cc = c.clone();
    cc[0].p.as_mut().unwrap()[3][1] = f64::NAN;
    expect_invalid(&m, &cc, &[case0, "field p", "value 3", "NaN"]);

    let mut cc = c.clone();
    cc[1].u.as_mut().unwrap()[0] = f64::INFINITY;
    expect_invalid(&m, &cc, &["level2-P1-P1-delta1.5e-2", "field u", "inf"]);

    let mut cc = c.clone();
    cc[0].lambda = Some((Centering::Node, vec![0.0; 2]));
    expect_invalid(&m, &cc, &[case0, "field lambda", "3 crack nodes"]);

    let mut cc = c.clone();
    cc[1].lambda = Some((Centering::Cell, vec![0.0; 5]));
    expect_invalid(&m, &cc, &["field lambda", "4 crack segments"]);

    let mut cc = c.clone();
    cc[0].lambda = Some((Centering::Cell, vec![0.0, f64::NAN]));
    expect_invalid(&m, &cc, &[case0, "field lambda", "value 1"]);

    let mut cc = c.clone();
    cc[0].jump = Some(vec![0.0; 2]);
    expect_invalid(&m, &cc, &[case0, "field jump", "3 crack nodes"]);

    let mut cc = c.clone();
    cc[1].jump.as_mut().unwrap()[4] = f64::NEG_INFINITY;
    expect_invalid(&m, &cc, &["field jump", "value 4"]);

    let mut cc = c.clone();
    cc[0].constants = vec![("jump".into(), 1.0)];
    expect_invalid(&m, &cc, &[case0, "constant field \"jump\""]);

    let mut cc = c.clone();
    cc[3].crack_points.truncate(1);
    expect_invalid(&m, &cc, &["odd <&>", "crack polyline"]);

    let mut cc = c.clone();
    cc[3].name = case0.into();
    expect_invalid(&m, &cc, &[case0, "twice"]);

    let mut cc = c.clone();
    cc[0].name = "a/b".into();
    expect_invalid(&m, &cc, &["a/b", "not a valid name"]);

    let mut cc = c.clone();
    cc[1].series = "level1-P1-P0.crack".into();
    expect_invalid(&m, &cc, &["level1-P1-P0.crack.series.xdmf", "clashes"]);

    let mut cc = c.clone();
    cc[1].name = "level1-P1-P0-delta1e-2.crack".into();
    expect_invalid(&m, &cc, &["level1-P1-P0-delta1e-2.crack.xdmf", "clashes"]);

    let mut cc = c.clone();
    cc[1].series = "level1-P1-P0".into();
    expect_invalid(&m, &cc, &["level2-P1-P1-delta1.5e-2", "mixes meshes"]);

    let mut cc = c.clone();
    cc[0].constants = vec![("u".into(), 1.0)];
    expect_invalid(&m, &cc, &[case0, "constant field \"u\""]);

    let mut cc = c.clone();
    cc[0].constants = vec![("delta".into(), f64::NAN)];
    expect_invalid(&m, &cc, &[case0, "not finite"]);

    let mut cc = c.clone();
    cc[0].series = "s:1".into();
    expect_invalid(&m, &cc, &["s:1", "not a valid name"]);

    let mut mm = m.clone();
    mm[0].triangles[1][2] = 9;
    expect_invalid(&mm, &c, &["level1-P1", "triangle 1", "node 9", "9 points"]);

    let mut mm = m.clone();
    mm[1].points[0][0] = f64::NAN;
    expect_invalid(&mm, &c, &["level2-P1", "points", "value 0"]);

    let mut mm = m.clone();
    mm[1].key = mm[0].key.clone();
    expect_invalid(&mm, &c, &["level1-P1", "twice"]);

    let tmp = tempfile::tempdir().unwrap();
    let e = write_fields(tmp.path(), "a:b", &m, &c).unwrap_err();
    assert!(matches!(e, OutputError::Invalid(_)), "{e}");
    assert!(listing(tmp.path()).is_empty());
}

#[test]
fn case_without_crack_or_fields() {
    let tmp = tempfile::tempdir().unwrap();
    let m = square_mesh("m", 1);
    let c = CaseFields {
        name: "bare".into(),
        mesh_key: "m".into(),
        u: None,
        p: None,
        p_bubble: None,
        crack_points: vec![],
        crack_segments: vec![],
        lambda: None,
        jump: None,
        series: "bare".into(),
        metadata: vec![],
        constants: vec![],
        extra: vec![],
    };
    let no_crack = CaseFields {
        jump: Some(vec![]),
        ..c.clone()
    };
    let e = write_fields(tmp.path(), "out", std::slice::from_ref(&m), &[no_crack]).unwrap_err();
    assert!(e.to_string().contains("crack polyline has 0 points"), "{e}");
    write_fields(tmp.path(), "out", &[m], &[c]).unwrap();
    assert_eq!(
        listing(&tmp.path().join("out")),
        ["bare.series.xdmf", "bare.xdmf"]
    );
    let xdmf = fs::read_to_string(tmp.path().join("out/bare.series.xdmf")).unwrap();
    assert!(!xdmf.contains("crack") && !xdmf.contains("Attribute"));
    let f = hdf5::File::open(tmp.path().join("out.h5")).unwrap();
    assert!(!f.link_exists("cases/bare/crack"));
}

/// A further field ([`CaseFields::extra`]) of each grid, kind and centering on the fixture's first
/// case: σ-like tensors per node, a vector per triangle, a scalar per crack node and segment.
fn with_extra(c: &CaseFields, mesh: &MeshData) -> CaseFields {
    use super::super::data::{Field, FieldKind, GridPart};
    let field = |name: &str, part, center, kind: FieldKind, items: usize| Field {
        name: name.into(),
        part,
        center,
        kind,
        values: (0..items * kind.components()).map(|i| i as f64).collect(),
    };
    let (n, t) = (mesh.points.len(), mesh.triangles.len());
    let (nc, ns) = (c.crack_points.len(), c.crack_segments.len());
    let mut c = c.clone();
    c.extra = vec![
        field(
            "sigma",
            GridPart::Mesh,
            Centering::Node,
            FieldKind::Tensor,
            n,
        ),
        field("u_h", GridPart::Mesh, Centering::Cell, FieldKind::Vector, t),
        field(
            "opening",
            GridPart::Crack,
            Centering::Node,
            FieldKind::Scalar,
            nc,
        ),
        field(
            "edge",
            GridPart::Crack,
            Centering::Cell,
            FieldKind::Scalar,
            ns,
        ),
    ];
    c
}

/// The further fields are written where the module documentation says (`/cases/CASE/NAME` and
/// `/cases/CASE/crack/NAME`, shaped (items[, components])) with an XDMF attribute of their type
/// and centering each; a field of the wrong length, of a reserved or repeated name, or on the
/// crack of a case without one is refused with nothing written.
#[test]
fn further_fields_are_written_and_validated() {
    let (m, c) = fixture();
    let mut cc = c.clone();
    cc[0] = with_extra(&c[0], &m[0]);
    let tmp = tempfile::tempdir().unwrap();
    write_fields(tmp.path(), "fields", &m, &cc).unwrap();
    let file = hdf5::File::open(tmp.path().join("fields.h5")).unwrap();
    let g = file.group(&format!("cases/{}", cc[0].name)).unwrap();
    let (n, t) = (m[0].points.len(), m[0].triangles.len());
    assert_eq!(g.dataset("sigma").unwrap().shape(), [n, 9]);
    assert_eq!(g.dataset("u_h").unwrap().shape(), [t, 3]);
    let opening = g.dataset("crack/opening").unwrap();
    assert_eq!(opening.shape(), [cc[0].crack_points.len()]);
    assert_eq!(opening.read_raw::<f64>().unwrap()[2], 2.0);
    assert!(opening.attr("delta").is_ok(), "the case's metadata");
    let xml = std::fs::read_to_string(tmp.path().join("fields").join(state_file(&cc[0].name, "")))
        .unwrap();
    assert!(xml.contains("<Attribute Name=\"sigma\" AttributeType=\"Tensor\" Center=\"Node\">"));
    assert!(xml.contains(&format!("Dimensions=\"{n} 9\"")));
    assert!(xml.contains("<Attribute Name=\"u_h\" AttributeType=\"Vector\" Center=\"Cell\">"));
    let crack = std::fs::read_to_string(
        tmp.path()
            .join("fields")
            .join(state_file(&cc[0].name, ".crack")),
    )
    .unwrap();
    assert!(crack.contains("<Attribute Name=\"opening\" AttributeType=\"Scalar\" Center=\"Node\">"));
    assert!(crack.contains("<Attribute Name=\"edge\" AttributeType=\"Scalar\" Center=\"Cell\">"));

    let case0 = cc[0].name.clone();
    let mut bad = cc.clone();
    bad[0].extra[0].values.pop();
    expect_invalid(&m, &bad, &[&case0, "field \"sigma\"", "its grid needs"]);
    let mut bad = cc.clone();
    bad[0].extra[1].name = "u".into();
    expect_invalid(&m, &bad, &[&case0, "field \"u\" clashes"]);
    let mut bad = cc.clone();
    bad[0].extra[3].name = "opening".into();
    expect_invalid(&m, &bad, &[&case0, "field \"opening\" clashes"]);
    let mut bad = cc.clone();
    bad[0].extra[2].values[1] = f64::NAN;
    expect_invalid(&m, &bad, &[&case0, "field opening", "value 1"]);
    let mut bad = cc.clone();
    bad[0].crack_points.clear();
    bad[0].crack_segments.clear();
    bad[0].lambda = None;
    bad[0].jump = None;
    expect_invalid(&m, &bad, &[&case0, "without a crack grid"]);
}
