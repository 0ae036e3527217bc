//! ParaView snapshots: VTK XML PolyData (`.vtp`) with one vertex per particle, and a `.pvd`
//! collection that lists the snapshots with their times.

use super::text::append_lines;
use crate::particles::Particles;
use std::fmt::Write;

/// Renders the particles as a `.vtp` document: points at the centres and point data
/// `id`, `radius` (m), `species`, `free` (1 free, 0 prescribed), `velocity` (m/s),
/// `angular_velocity` (rad/s), `force` (N), `part` (wall part, −1 for none), plus the
/// per-slot scalars of `extra` (name, values by slot). Particles are written in id order.
pub fn particles_vtp(p: &Particles, extra: &[(&str, Vec<f64>)]) -> String {
    let n = p.len();
    let slot = p.slot_of();
    let order: Vec<usize> = slot.iter().map(|&s| s as usize).collect();
    let mut s = String::with_capacity(n * 200);
    let _ = write!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
         <PolyData>\n<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\">\n<Points>\n\
         <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n"
    );
    append_lines(&mut s, &order, |s, &i| {
        let r = p.position[i];
        let _ = writeln!(s, "{:e} {:e} {:e}", r.x, r.y, r.z);
    });
    s.push_str("</DataArray>\n</Points>\n<Verts>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for k in 0..n {
        let _ = write!(s, "{k} ");
    }
    s.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for k in 1..=n {
        let _ = write!(s, "{k} ");
    }
    s.push_str("\n</DataArray>\n</Verts>\n<PointData Scalars=\"radius\" Vectors=\"velocity\">\n");
    scalar(&mut s, "id", "Int64", &order, |s, i| {
        let _ = write!(s, "{} ", p.id[i]);
    });
    scalar(&mut s, "radius", "Float64", &order, |s, i| {
        let _ = write!(s, "{:e} ", p.radius[i]);
    });
    scalar(&mut s, "species", "Int32", &order, |s, i| {
        let _ = write!(s, "{} ", p.species[i]);
    });
    scalar(&mut s, "free", "Int32", &order, |s, i| {
        let _ = write!(s, "{} ", u8::from(p.motion[i].is_free()));
    });
    scalar(&mut s, "part", "Int32", &order, |s, i| {
        match p.part.get(i) {
            Some(&part) if part != crate::observe::NO_PART => {
                let _ = write!(s, "{part} ");
            }
            _ => s.push_str("-1 "),
        }
    });
    for (name, values) in extra {
        scalar(&mut s, name, "Float64", &order, |s, i| {
            let _ = write!(s, "{:e} ", values[i]);
        });
    }
    vector(&mut s, "velocity", &order, |i| p.velocity[i]);
    vector(&mut s, "angular_velocity", &order, |i| {
        p.angular_velocity[i]
    });
    vector(&mut s, "force", &order, |i| p.force[i]);
    s.push_str("</PointData>\n</Piece>\n</PolyData>\n</VTKFile>\n");
    s
}

/// A one-component data array: `value` writes slot `i`'s entry and its trailing space.
fn scalar(
    s: &mut String,
    name: &str,
    ty: &str,
    order: &[usize],
    value: impl Fn(&mut String, usize) + Sync,
) {
    let _ = writeln!(
        s,
        "<DataArray type=\"{ty}\" Name=\"{name}\" format=\"ascii\">"
    );
    append_lines(s, order, |s, &i| value(s, i));
    s.push_str("\n</DataArray>\n");
}

/// A three-component data array, one line per slot in `order`.
fn vector(
    s: &mut String,
    name: &str,
    order: &[usize],
    value: impl Fn(usize) -> glam::DVec3 + Sync,
) {
    let _ = writeln!(
        s,
        "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
    );
    append_lines(s, order, |s, &i| {
        let v = value(i);
        let _ = writeln!(s, "{:e} {:e} {:e}", v.x, v.y, v.z);
    });
    s.push_str("</DataArray>\n");
}

/// Renders a `.pvd` collection of `(time, file name)` snapshots.
pub fn collection_pvd(entries: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
    );
    for (t, f) in entries {
        let _ = writeln!(s, "<DataSet timestep=\"{t:e}\" file=\"{f}\"/>");
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::{Motion, Sphere};
    use glam::DVec3;

    #[test]
    fn vtp_lists_every_particle_in_id_order() {
        let mut p = Particles::default();
        for k in 0..3 {
            p.push(
                Sphere {
                    position: DVec3::new(k as f64, 0.0, 0.0),
                    velocity: DVec3::ZERO,
                    angular_velocity: DVec3::ZERO,
                    radius: 0.5 + k as f64,
                    species: 0,
                    motion: Motion::Free,
                },
                1.0,
            );
        }
        p.permute(&[2, 0, 1]);
        let doc = particles_vtp(&p, &[]);
        assert!(doc.contains("NumberOfPoints=\"3\""));
        assert!(doc.contains("0e0 0e0 0e0\n1e0 0e0 0e0\n2e0 0e0 0e0\n"));
        assert!(doc.contains("5e-1 1.5e0 2.5e0"));
        assert!(doc.ends_with("</VTKFile>\n"));
    }
}
