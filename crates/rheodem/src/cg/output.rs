//! Writing fields: a CSV table (one row per grid point) and a VTK image (`.vti`) for
//! ParaView. The axisymmetric grid appears in VTK as the `x–z` plane (`x` = `r`).

use super::fields::FieldPoint;
use super::grid::Grid;
use crate::io::text::append_lines;
use std::fmt::Write;

/// The scalar columns after the coordinates, with how to read each from a point.
type Column = (&'static str, fn(&FieldPoint) -> f64);

const SCALARS: [Column; 12] = [
    ("density", |p| p.density),
    ("volume_fraction", |p| p.volume_fraction),
    ("pressure", |p| p.pressure),
    ("shear_stress", |p| p.shear_stress),
    ("resolved_shear_stress", |p| p.resolved_shear_stress),
    ("strain_rate", |p| p.strain_rate),
    ("friction", |p| p.friction),
    ("inertial_number", |p| p.inertial_number),
    ("softness", |p| p.softness),
    ("bond_number", |p| p.bond_number),
    ("coordination", |p| p.coordination),
    ("bridges_per_particle", |p| p.bridges_per_particle),
];

/// A tensor field, by name, with how to read it from a point.
type TensorColumn = (&'static str, fn(&FieldPoint) -> &[f64; 9]);

/// The tensor fields.
const TENSORS: [TensorColumn; 3] = [
    ("stress", |p| &p.stress),
    ("kinetic_stress", |p| &p.kinetic_stress),
    ("contact_stress", |p| &p.contact_stress),
];

/// The fields as CSV: the grid's coordinates (m), the scalars, the velocity components and
/// the three stress tensors component by component (`stress_rphi` is `σ_rφ`), SI units,
/// `NaN` where a quantity is undefined.
pub fn to_csv(grid: &Grid, points: &[FieldPoint]) -> String {
    let comps = grid.component_names();
    let mut header: Vec<String> = grid.axis_names().iter().map(|s| s.to_string()).collect();
    header.extend(SCALARS.iter().map(|(n, _)| n.to_string()));
    header.extend(comps.iter().map(|c| format!("velocity_{c}")));
    for (name, _) in TENSORS {
        for a in comps {
            for b in comps {
                header.push(format!("{name}_{a}{b}"));
            }
        }
    }
    let mut out = header.join(",");
    out.push('\n');
    append_lines(&mut out, points, |row, p| {
        let values = p
            .coordinates
            .iter()
            .copied()
            .chain(SCALARS.iter().map(|(_, f)| f(p)));
        let values = values
            .chain(p.velocity)
            .chain(TENSORS.iter().flat_map(|(_, f)| *f(p)));
        for (k, x) in values.enumerate() {
            let sep = if k == 0 { "" } else { "," };
            let _ = write!(row, "{sep}{x:e}");
        }
        row.push('\n');
    });
    out
}

/// The fields as a VTK XML image (`.vti`, ASCII): scalars, the velocity as a vector and the
/// stresses as tensors, in the grid's components.
pub fn to_vti(grid: &Grid, points: &[FieldPoint]) -> String {
    let ax = grid.axes();
    // Map the grid's axes onto VTK's x, y, z.
    let vtk_axis: Vec<usize> = match grid {
        Grid::Cartesian { .. } => vec![0, 1, 2],
        Grid::Slab { axis, .. } => vec![*axis],
        Grid::Axisymmetric { .. } => vec![0, 2],
    };
    let mut extent = [0usize; 3];
    let mut origin = [0.0; 3];
    let mut spacing = [1.0; 3];
    for (a, &v) in vtk_axis.iter().enumerate() {
        extent[v] = ax.n[a] - 1;
        origin[v] = ax.point(a, 0);
        spacing[v] = ax.h[a];
    }
    let ext = format!("0 {} 0 {} 0 {}", extent[0], extent[1], extent[2]);
    let mut s = String::new();
    let _ = writeln!(s, "<?xml version=\"1.0\"?>");
    let _ = writeln!(
        s,
        "<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">"
    );
    let _ = writeln!(
        s,
        "  <ImageData WholeExtent=\"{ext}\" Origin=\"{:e} {:e} {:e}\" Spacing=\"{:e} {:e} {:e}\">",
        origin[0], origin[1], origin[2], spacing[0], spacing[1], spacing[2]
    );
    let _ = writeln!(s, "    <Piece Extent=\"{ext}\">");
    let _ = writeln!(
        s,
        "      <PointData Scalars=\"volume_fraction\" Vectors=\"velocity\">"
    );
    // A data array on one line, its values separated by spaces: `values` writes a point's
    // components, each followed by a space, and the last space is dropped.
    let mut array = |name: &str,
                     comps: usize,
                     values: &(dyn Fn(&mut String, &FieldPoint) + Sync)| {
        let _ = writeln!(
            s,
            "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{comps}\" \
             format=\"ascii\">"
        );
        s.push_str("          ");
        append_lines(&mut s, points, values);
        if !points.is_empty() {
            s.pop();
        }
        s.push('\n');
        let _ = writeln!(s, "        </DataArray>");
    };
    for (name, f) in SCALARS {
        array(name, 1, &|s, p| spaced(s, &[f(p)]));
    }
    array("velocity", 3, &|s, p| spaced(s, &p.velocity));
    for (name, f) in TENSORS {
        array(name, 9, &|s, p| spaced(s, f(p)));
    }
    let _ = writeln!(s, "      </PointData>");
    let _ = writeln!(s, "    </Piece>");
    let _ = writeln!(s, "  </ImageData>");
    let _ = writeln!(s, "</VTKFile>");
    s
}

/// Writes each of `values` followed by a space.
fn spaced(s: &mut String, values: &[f64]) {
    for x in values {
        let _ = write!(s, "{x:e} ");
    }
}
