//! Writing fields: a CSV table (one row per grid point) and a VTK image (`.vti`) for
//! ParaView. The axisymmetric grid appears in VTK as the `x–z` plane (`x` = `r`).

use super::fields::FieldPoint;
use super::grid::Grid;
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
    for p in points {
        let mut row: Vec<String> = p.coordinates.iter().map(|x| format!("{x:e}")).collect();
        row.extend(SCALARS.iter().map(|(_, f)| format!("{:e}", f(p))));
        row.extend(p.velocity.iter().map(|x| format!("{x:e}")));
        for (_, f) in TENSORS {
            row.extend(f(p).iter().map(|x| format!("{x:e}")));
        }
        out.push_str(&row.join(","));
        out.push('\n');
    }
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
    let mut array = |name: &str, comps: usize, values: &mut dyn Iterator<Item = f64>| {
        let _ = writeln!(
            s,
            "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{comps}\" \
             format=\"ascii\">"
        );
        let line: Vec<String> = values.map(|x| format!("{x:e}")).collect();
        let _ = writeln!(s, "          {}", line.join(" "));
        let _ = writeln!(s, "        </DataArray>");
    };
    for (name, f) in SCALARS {
        array(name, 1, &mut points.iter().map(f));
    }
    array(
        "velocity",
        3,
        &mut points.iter().flat_map(|p| p.velocity.into_iter()),
    );
    for (name, f) in TENSORS {
        array(
            name,
            9,
            &mut points.iter().flat_map(|p| f(p).iter().copied()),
        );
    }
    let _ = writeln!(s, "      </PointData>");
    let _ = writeln!(s, "    </Piece>");
    let _ = writeln!(s, "  </ImageData>");
    let _ = writeln!(s, "</VTKFile>");
    s
}
