//! Checks of a run's ParaView files: every HDF5 reference of every XDMF file exists with the
//! shape the XDMF states, a time series' times increase, and an independent reader, meshio
//! (Debian's python3-meshio, installed by scripts/setup), reads the brake and the series.

use std::path::Path;
use std::process::Command;

/// The `(dimensions, file:dataset)` of every HDF DataItem of an XDMF text.
fn data_items(xdmf: &str) -> Vec<(Vec<usize>, String)> {
    let mut out = Vec::new();
    for part in xdmf.split("<DataItem ").skip(1) {
        let (head, rest) = part.split_once('>').expect("DataItem closes its tag");
        let text = rest.split("</DataItem>").next().expect("DataItem ends");
        let dims = head
            .split("Dimensions=\"")
            .nth(1)
            .and_then(|d| d.split('"').next())
            .expect("DataItem has Dimensions");
        let dims: Vec<usize> = dims
            .split_whitespace()
            .map(|d| d.parse().expect("a dimension is a number"))
            .collect();
        assert!(head.contains("Format=\"HDF\""), "not an HDF item: {head}");
        out.push((dims, text.trim().to_string()));
    }
    out
}

/// The `<Time Value=...>` values of an XDMF text, in order.
fn times(xdmf: &str) -> Vec<f64> {
    xdmf.split("<Time Value=\"")
        .skip(1)
        .map(|t| t.split('"').next().unwrap().parse().expect("a time"))
        .collect()
}

/// Every XDMF file in `results` refers to datasets that exist with the stated shape; returns
/// the number of references checked per file.
pub fn check_xdmf_references(results: &Path) -> Vec<(String, usize)> {
    let mut checked = Vec::new();
    for name in ["results.xdmf", "surfaces.xdmf", "vibration.xdmf"] {
        let path = results.join(name);
        let xdmf =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let items = data_items(&xdmf);
        assert!(!items.is_empty(), "{name} refers to nothing");
        let mut files = std::collections::BTreeMap::new();
        for (dims, reference) in &items {
            let (file, dataset) = reference.split_once(':').expect("file:dataset");
            let h5 = files.entry(file.to_string()).or_insert_with(|| {
                hdf5::File::open(results.join(file))
                    .unwrap_or_else(|e| panic!("{name} refers to {file}, which does not open: {e}"))
            });
            let ds = h5
                .dataset(dataset)
                .unwrap_or_else(|e| panic!("{name}: {file}:{dataset} missing: {e}"));
            assert_eq!(&ds.shape(), dims, "{name}: {file}:{dataset}");
        }
        let t = times(&xdmf);
        assert!(
            t.windows(2).all(|w| w[1] > w[0]) && t.iter().all(|x| x.is_finite()),
            "{name}: the frame times do not increase: {t:?}"
        );
        checked.push((name.to_string(), items.len()));
    }
    checked
}

const MESHIO_CHECK: &str = r#"
import sys, meshio, numpy as np
folder = sys.argv[1]
m = meshio.read(folder + "/results.xdmf")
cells = sum(len(b.data) for b in m.cells)
bad = [k for k, v in m.point_data.items() if not np.all(np.isfinite(v))]
assert not bad, f"fields with NaN or inf: {bad}"
assert any(k.startswith("static contact pressure") for k in m.point_data), list(m.point_data)
with meshio.xdmf.TimeSeriesReader(folder + "/vibration.xdmf") as r:
    points, _ = r.read_points_cells()
    ts, peak = [], 0.0
    for k in range(r.num_steps):
        t, data, _ = r.read_data(k)
        v = data["vibration (m)"]
        assert v.shape == (len(points), 3) and np.all(np.isfinite(v)), (k, v.shape)
        ts.append(t)
        peak = max(peak, float(np.abs(v).max()))
assert all(b > a for a, b in zip(ts, ts[1:])), ts
print(len(m.points), cells, len(m.point_data), r.num_steps, peak)
"#;

/// What meshio read: points, cells, nodal fields of results.xdmf; frames of vibration.xdmf
/// and the largest vibration component in them (m).
pub struct MeshioView {
    pub points: usize,
    pub cells: usize,
    pub fields: usize,
    pub frames: usize,
    pub peak: f64,
}

/// Debian's python3 (where python3-meshio lives) reads the files of `results`.
pub fn read_with_meshio(results: &Path) -> MeshioView {
    let out = Command::new("/usr/bin/python3")
        .args(["-c", MESHIO_CHECK])
        .arg(results)
        .output()
        .expect("/usr/bin/python3 runs (scripts/setup installs python3-meshio)");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "meshio could not read the XDMF files of {}:\n{stdout}\n{}",
        results.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Vec<&str> = stdout.split_whitespace().collect();
    assert_eq!(v.len(), 5, "{stdout}");
    MeshioView {
        points: v[0].parse().unwrap(),
        cells: v[1].parse().unwrap(),
        fields: v[2].parse().unwrap(),
        frames: v[3].parse().unwrap(),
        peak: v[4].parse().unwrap(),
    }
}
