//! Contact maps: a per-point field of one interface drawn in the disc plane (mm, centred on
//! the rotation axis, seen from the axis' tip), each master face split into the parametric
//! cells of its Gauss points and filled with the point's value; the pad's outline, a colour
//! bar with values and units, and an arrow for the disc's direction of motion.

use std::collections::BTreeMap;
use std::path::Path;

use crate::contact::pairing::{Axis, ContactPoint};
use crate::contact::surface::{cross, dot, sub, Face};
use crate::fem::quadrature::gauss_legendre;
use crate::io::figure::{Figure, BLACK, RED};
use crate::mesh::Mesh;
use crate::stages::model::Model;
use crate::stages::statics::Preloaded;
use crate::stages::Analyses;

/// Where the points of one interface are: the mesh, the points, their quadrature and the disc.
#[derive(Clone, Copy)]
pub struct MapContext<'a> {
    pub mesh: &'a Mesh,
    pub points: &'a [ContactPoint],
    pub gauss: usize,
    pub axis: Axis,
    /// rad/s, sign by the right-hand rule about the axis.
    pub disc_speed: f64,
}

impl<'a> MapContext<'a> {
    /// The contact points of a preloaded model (built once per run; every map uses it).
    pub fn new(model: &'a Model, preload: &'a Preloaded) -> Self {
        let settings = &preload.contact_settings;
        MapContext {
            mesh: &model.mesh,
            points: preload.contact.points(),
            gauss: settings.gauss_points,
            axis: settings.axis(),
            disc_speed: settings.disc_speed,
        }
    }

    /// The run's contact points, when it has a mesh model and a static state.
    pub fn of(a: &'a Analyses) -> Option<Self> {
        Some(Self::new(a.model.as_ref()?, a.preload.as_ref()?))
    }
}

/// One interface in the disc plane (mm): a polygon per point, the boundary edges of its
/// faces, and the disc's direction of motion at the centroid (unit vector).
pub struct PlaneMap {
    pub cells: Vec<(Vec<(f64, f64)>, usize)>,
    pub outline: Vec<[(f64, f64); 2]>,
    pub centroid: (f64, f64),
    pub motion: (f64, f64),
    pub x: (f64, f64),
    pub y: (f64, f64),
}

/// Writes the map of `values` (one per point, point-id order) on `interface` as PNG and SVG,
/// titled `title`, colour bar labelled `label` (with units); nothing when the interface has
/// no point.
pub fn write_map(
    path: &Path,
    context: MapContext,
    values: &[f64],
    interface: usize,
    title: &str,
    label: &str,
) -> std::io::Result<()> {
    let Some(map) = plane_map(context, interface) else {
        return Ok(());
    };
    let range = value_range(&map, values);
    map_figure(&map, values, (900, 640), title, label, range).save(path)
}

/// The finite values' range over the map's points.
pub fn value_range(map: &PlaneMap, values: &[f64]) -> (f64, f64) {
    map.cells
        .iter()
        .map(|&(_, i)| values[i])
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        })
}

/// The map drawn as a figure of `size` pixels with its colour bar over `range`.
pub fn map_figure(
    map: &PlaneMap,
    values: &[f64],
    size: (usize, usize),
    title: &str,
    label: &str,
    range: (f64, f64),
) -> Figure {
    let pad = 0.06 * (map.x.1 - map.x.0).max(map.y.1 - map.y.0);
    let mut fig = Figure::new(
        size.0,
        size.1,
        (map.x.0 - pad, map.x.1 + pad),
        (map.y.0 - pad, map.y.1 + pad),
        title,
        "x in the disc plane (mm)",
        "y in the disc plane (mm)",
    )
    .equal_aspect()
    .colour_bar(label, range);
    fig.polygons(
        map.cells
            .iter()
            .map(|(p, i)| (p.clone(), values[*i]))
            .collect(),
    );
    fig.segments(map.outline.clone(), BLACK);
    let length = 0.25 * (map.x.1 - map.x.0).max(map.y.1 - map.y.0);
    let (c, m) = (map.centroid, map.motion);
    fig.arrow(
        (c.0 - 0.5 * length * m.0, c.1 - 0.5 * length * m.1),
        (c.0 + 0.5 * length * m.0, c.1 + 0.5 * length * m.1),
        RED,
        "disc motion",
    );
    fig
}

/// The polygons of the points of `interface` in the disc plane, or None without points.
pub fn plane_map(context: MapContext, interface: usize) -> Option<PlaneMap> {
    let MapContext {
        mesh,
        points,
        gauss,
        axis,
        disc_speed,
    } = context;
    // In-plane frame: e1 = any direction normal to the axis, e2 = axis x e1 (seen from the
    // axis' tip, positive rotation is counter-clockwise).
    let a = axis.direction;
    let seed = if a[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = {
        let t = sub(seed, crate::contact::surface::scale(a, dot(seed, a)));
        crate::contact::surface::normalize(t)
    };
    let e2 = cross(a, e1);
    let plane = |x: [f64; 3]| {
        let d = sub(x, axis.center);
        (1e3 * dot(d, e1), 1e3 * dot(d, e2))
    };
    let mine: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].interface == interface)
        .collect();
    if mine.is_empty() {
        return None;
    }
    let (gp, _) = gauss_legendre(gauss.clamp(1, 4));
    let mut bounds = vec![-1.0];
    bounds.extend(gp.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    bounds.push(1.0);
    let cell = |x: f64| gp.iter().position(|&g| (g - x).abs() < 1e-9);
    let mut cells = Vec::new();
    // Face edges by their end nodes: an edge of one face only is on the outline.
    type Edge = ((f64, f64), (f64, f64), usize); // ends in the plane, faces using it
                                                 // Ordered, so the outline is drawn in the same order every run (byte-identical figures).
    let mut edges: BTreeMap<(usize, usize), Edge> = BTreeMap::new();
    let mut seen = std::collections::HashSet::new();
    for &i in &mine {
        let p = &points[i];
        let face = Face::new(mesh, p.master_face.0, p.master_face.1);
        let corners = if face.shape.is_triangle() { 3 } else { 4 };
        let polygon: Vec<(f64, f64)> = match (
            face.shape.is_triangle(),
            cell(p.master_xi[0]),
            cell(p.master_xi[1]),
        ) {
            (false, Some(ci), Some(cj)) => [
                [bounds[ci], bounds[cj]],
                [bounds[ci + 1], bounds[cj]],
                [bounds[ci + 1], bounds[cj + 1]],
                [bounds[ci], bounds[cj + 1]],
            ]
            .iter()
            .map(|&xi| plane(face.at(xi).x))
            .collect(),
            // Triangles: the point's share of the face, drawn as the whole face.
            _ => face
                .coords
                .iter()
                .take(corners)
                .map(|&x| plane(x))
                .collect(),
        };
        cells.push((polygon, i));
        if seen.insert(p.master_face) {
            for k in 0..corners {
                let (u, v) = (face.nodes[k], face.nodes[(k + 1) % corners]);
                let key = (u.min(v), u.max(v));
                let ends = (plane(face.coords[k]), plane(face.coords[(k + 1) % corners]));
                edges.entry(key).or_insert((ends.0, ends.1, 0)).2 += 1;
            }
        }
    }
    let outline = edges
        .values()
        .filter(|e| e.2 == 1)
        .map(|e| [e.0, e.1])
        .collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut sum = (0.0, 0.0);
    for (polygon, _) in &cells {
        for q in polygon {
            lo = [lo[0].min(q.0), lo[1].min(q.1)];
            hi = [hi[0].max(q.0), hi[1].max(q.1)];
        }
        let n = polygon.len() as f64;
        sum.0 += polygon.iter().map(|q| q.0).sum::<f64>() / n;
        sum.1 += polygon.iter().map(|q| q.1).sum::<f64>() / n;
    }
    let centroid = (sum.0 / cells.len() as f64, sum.1 / cells.len() as f64);
    // The disc's surface velocity omega a x r is, in the plane, r turned by +90 degrees.
    let r = (centroid.0 * centroid.0 + centroid.1 * centroid.1)
        .sqrt()
        .max(1e-300);
    let sign = if disc_speed < 0.0 { -1.0 } else { 1.0 };
    Some(PlaneMap {
        cells,
        outline,
        centroid,
        motion: (-sign * centroid.1 / r, sign * centroid.0 / r),
        x: (lo[0], hi[0]),
        y: (lo[1], hi[1]),
    })
}
