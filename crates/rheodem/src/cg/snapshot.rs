//! What the coarse-graining reads from a simulation: particles and contacts at one instant
//! (docs/coarse-graining.md §3).
//!
//! A [`Snapshot`] is assembled from plain records — [`ParticleRecord`] and
//! [`ContactRecord`] — which are also what the snapshot files hold, so that coarse-graining a
//! run while it goes and coarse-graining its stored snapshots afterwards run the same code on
//! the same numbers.

use super::grid::Grid;
use crate::domain::{Domain, IDENTITY_IMAGE, IMAGE_COUNT, ImageTransform, image_offsets};
use crate::io::text::append_lines;
use crate::observe::{ContactObserver, ContactView};
use crate::particles::Particles;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// One particle of a snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParticleRecord {
    /// Permanent id.
    pub id: u32,
    /// Centre (m).
    pub position: DVec3,
    /// Velocity (m/s).
    pub velocity: DVec3,
    /// Radius (m).
    pub radius: f64,
    /// Mass (kg).
    pub mass: f64,
    /// Whether the particle moves under its forces (wall particles do not).
    pub free: bool,
    /// Angular velocity (rad/s); `NaN` when read from a file of a version that did not
    /// record it.
    pub angular_velocity: DVec3,
}

impl ParticleRecord {
    /// The records of every particle.
    pub fn all(p: &Particles) -> Vec<ParticleRecord> {
        (0..p.len())
            .map(|i| ParticleRecord {
                id: p.id[i],
                position: p.position[i],
                velocity: p.velocity[i],
                radius: p.radius[i],
                mass: p.mass[i],
                free: p.motion[i].is_free(),
                angular_velocity: p.angular_velocity[i],
            })
            .collect()
    }
}

/// One interacting pair `(i, j)` of a snapshot, with what each side needs in its own frame
/// (the frames differ when `j` is seen through a rotated image).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactRecord {
    /// Id of `i`.
    pub i: u32,
    /// Id of `j`, or the index of an analytic wall.
    pub j: u32,
    /// Whether `j` is an analytic wall.
    pub wall: bool,
    /// Overlap `δ` (m); negative for a pair apart that attracts.
    pub overlap: f64,
    /// Centre of `i` (m).
    pub centre_i: DVec3,
    /// Branch `r_i − r_j` through the image (m); for a wall, from the foot on the wall to
    /// the centre.
    pub branch: DVec3,
    /// Contact point in `i`'s frame (m).
    pub point_i: DVec3,
    /// Force on `i` (N).
    pub force_i: DVec3,
    /// Centre of `j` in its own frame (m); for a wall, the foot.
    pub centre_j: DVec3,
    /// Contact point in `j`'s frame (m).
    pub point_j: DVec3,
    /// Force on `j` in `j`'s frame (N).
    pub force_j: DVec3,
}

/// A contact observer that keeps every interacting pair as a [`ContactRecord`].
#[derive(Clone, Debug, Default)]
pub struct ContactRecords(pub Vec<ContactRecord>);

impl ContactObserver for ContactRecords {
    fn visit(&mut self, c: &ContactView<'_>) {
        let centre_j = c.image.position_back(c.position - c.branch);
        self.0.push(ContactRecord {
            i: c.ids[0],
            j: c.ids[1],
            wall: c.wall.is_some(),
            overlap: c.kinematics.overlap,
            centre_i: c.position,
            branch: c.branch,
            point_i: c.contact_point(),
            force_i: c.force.force,
            centre_j,
            point_j: c.contact_point_of_j(),
            force_j: c.force_on_j(),
        });
    }

    fn merge(&mut self, other: Self) {
        self.0.extend(other.0);
    }
}

/// A particle as the coarse-graining sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Centre (m).
    pub position: DVec3,
    /// Velocity (m/s).
    pub velocity: DVec3,
    /// Mass (kg).
    pub mass: f64,
    /// Volume (m³).
    pub volume: f64,
    /// Touching contacts (`δ > 0`, wall particles and walls included).
    pub contacts: u32,
    /// Attracting pairs apart (open bridges).
    pub bridges: u32,
}

/// A contact's share of the stress: `f ⊗ (to − from)`, spread along the segment from
/// `from` to `to` (m), `f` (N) the force on the particle at `to`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Start (m).
    pub from: DVec3,
    /// End (m): the centre of the free particle the force acts on.
    pub to: DVec3,
    /// Force (N).
    pub force: DVec3,
}

/// The free particles and contact segments of one instant, with the periodic images the
/// grid must see them through.
#[derive(Clone, Debug, Default)]
pub struct Snapshot {
    /// Time (s).
    pub time: f64,
    /// The free particles.
    pub bodies: Vec<Body>,
    /// The contacts' segments.
    pub segments: Vec<Segment>,
    /// Images of the domain besides the identity (translations, Lees-Edwards shifts,
    /// wedge rotations).
    pub images: Vec<ImageTransform>,
}

impl Snapshot {
    /// Assembles a snapshot: only free particles count as material. A contact between two
    /// free particles is spread along its branch; a contact of a free particle with a wall
    /// particle or an analytic wall along the segment from the contact point to the free
    /// particle's centre; a pair of two wall particles not at all. Particles absent from
    /// `particles` count as walls.
    pub fn assemble(
        time: f64,
        particles: &[ParticleRecord],
        contacts: &[ContactRecord],
        images: Vec<ImageTransform>,
    ) -> Snapshot {
        let max_id = particles
            .iter()
            .map(|p| p.id as usize + 1)
            .max()
            .unwrap_or(0);
        let mut slot = vec![usize::MAX; max_id];
        for (k, p) in particles.iter().enumerate() {
            slot[p.id as usize] = k;
        }
        let free_slot = |id: u32| {
            slot.get(id as usize)
                .copied()
                .filter(|&k| k != usize::MAX && particles[k].free)
        };
        let mut counts = vec![(0u32, 0u32); particles.len()];
        let mut segments = Vec::with_capacity(contacts.len());
        for c in contacts {
            let si = free_slot(c.i);
            let sj = if c.wall { None } else { free_slot(c.j) };
            for s in [si, sj].into_iter().flatten() {
                if c.overlap > 0.0 {
                    counts[s].0 += 1;
                } else {
                    counts[s].1 += 1;
                }
            }
            match (si, sj) {
                (Some(_), Some(_)) => segments.push(Segment {
                    from: c.centre_i - c.branch,
                    to: c.centre_i,
                    force: c.force_i,
                }),
                (Some(_), None) => segments.push(Segment {
                    from: c.point_i,
                    to: c.centre_i,
                    force: c.force_i,
                }),
                (None, Some(_)) => segments.push(Segment {
                    from: c.point_j,
                    to: c.centre_j,
                    force: c.force_j,
                }),
                (None, None) => {}
            }
        }
        let bodies = particles
            .iter()
            .zip(&counts)
            .filter(|(p, _)| p.free)
            .map(|(p, &(contacts, bridges))| Body {
                position: p.position,
                velocity: p.velocity,
                mass: p.mass,
                volume: 4.0 / 3.0 * std::f64::consts::PI * p.radius.powi(3),
                contacts,
                bridges,
            })
            .collect();
        Snapshot {
            time,
            bodies,
            segments,
            images,
        }
    }

    /// Body `k` and those of its images that reach the grid within `reach` (m).
    pub(crate) fn body_images<'a>(
        &'a self,
        k: usize,
        grid: &'a Grid,
        reach: f64,
    ) -> impl Iterator<Item = Body> + 'a {
        let b = self.bodies[k];
        std::iter::once(&ImageTransform::IDENTITY)
            .chain(&self.images)
            .map(move |t| Body {
                position: t.position(b.position),
                velocity: t.velocity(b.velocity),
                ..b
            })
            .filter(move |b| grid.reaches(b.position, reach))
    }

    /// Segment `k` and those of its images that reach the grid within `reach` (m).
    pub(crate) fn segment_images<'a>(
        &'a self,
        k: usize,
        grid: &'a Grid,
        reach: f64,
    ) -> impl Iterator<Item = Segment> + 'a {
        let s = self.segments[k];
        std::iter::once(&ImageTransform::IDENTITY)
            .chain(&self.images)
            .map(move |t| Segment {
                from: t.position(s.from),
                to: t.position(s.to),
                force: t.vector(s.force),
            })
            // Every point of the segment lies within its length of its end.
            .filter(move |s| grid.reaches(s.to, reach + (s.to - s.from).length()))
    }
}

/// The images a grid must see a domain's particles through: none for the axisymmetric grid
/// (its ring average covers the azimuth, and so a wedge's rotated images); a wedge's two
/// rotations for the other grids; otherwise the translations (with the Lees-Edwards shift
/// and velocity jump) along the periodic axes — for a slab grid only along its axis.
pub fn images_for(domain: &Domain, grid: &Grid) -> Vec<ImageTransform> {
    if matches!(grid, Grid::Axisymmetric { .. }) {
        return Vec::new();
    }
    let all = domain.image_transforms();
    if domain.as_wedge().is_some() {
        return domain
            .rotated_images()
            .iter()
            .map(|&(code, _)| all[code as usize])
            .collect();
    }
    // A slab averages over the plane normal to its axis: images across that plane's
    // periodic axes would count the same particles again.
    let along = |a: usize| match grid {
        Grid::Slab { axis, .. } => a == *axis,
        _ => true,
    };
    (0..IMAGE_COUNT as u8)
        .filter(|&code| code != IDENTITY_IMAGE)
        .filter(|&code| {
            let o = image_offsets(code);
            (0..3).all(|a| o[a] == 0 || (domain.periodic[a] && along(a)))
        })
        .map(|code| all[code as usize])
        .collect()
}

/// Columns of a particle file (`snapshot-N.particles.csv`).
pub const PARTICLE_COLUMNS: &str = "id,x,y,z,vx,vy,vz,radius,mass,free,wx,wy,wz";

/// Columns of the particle files written before the angular velocity was recorded; they
/// still read, with the angular velocity `NaN`.
const PARTICLE_COLUMNS_NO_SPIN: &str = "id,x,y,z,vx,vy,vz,radius,mass,free";

/// Columns of a contact file (`snapshot-N.contacts.csv`): ids, whether `j` is an analytic
/// wall, the overlap, then `i`'s centre, branch, contact point and force, and `j`'s centre,
/// contact point and force in its own frame.
pub const CONTACT_COLUMNS: &str = "i,j,wall,overlap,xi,yi,zi,bx,by,bz,cix,ciy,ciz,fix,fiy,fiz,\
                                   xj,yj,zj,cjx,cjy,cjz,fjx,fjy,fjz";

/// Appends `,x,y,z` with every component written so that it reads back exactly.
fn push_vec(row: &mut String, v: DVec3) {
    let _ = write!(row, ",{:e},{:e},{:e}", v.x, v.y, v.z);
}

/// The particle records as CSV, every number written so that it reads back exactly.
pub fn particles_csv(records: &[ParticleRecord]) -> String {
    let mut out = format!("{PARTICLE_COLUMNS}\n");
    append_lines(&mut out, records, |row, p| {
        let _ = write!(row, "{}", p.id);
        push_vec(row, p.position);
        push_vec(row, p.velocity);
        let _ = write!(row, ",{:e},{:e},{}", p.radius, p.mass, u8::from(p.free));
        push_vec(row, p.angular_velocity);
        row.push('\n');
    });
    out
}

/// The contact records as CSV, every number written so that it reads back exactly.
pub fn contacts_csv(records: &[ContactRecord]) -> String {
    let mut out = format!("{CONTACT_COLUMNS}\n");
    append_lines(&mut out, records, |row, c| {
        let _ = write!(row, "{},{},{},{:e}", c.i, c.j, u8::from(c.wall), c.overlap);
        for v in [
            c.centre_i, c.branch, c.point_i, c.force_i, c.centre_j, c.point_j, c.force_j,
        ] {
            push_vec(row, v);
        }
        row.push('\n');
    });
    out
}

/// Splits the rows of a CSV text with the given header into numbers, naming the file
/// (`what`), the line and the field of the first one that is not a number.
fn rows(text: &str, header: &str, what: &str) -> Result<Vec<Vec<f64>>, super::CgError> {
    let bad = |m: String| super::CgError::Invalid(format!("{what}: {m}"));
    let mut lines = text.lines();
    match lines.next() {
        Some(h) if h.trim() == header => {}
        other => {
            return Err(bad(format!(
                "the first line must be the header `{header}`, found `{}`",
                other.unwrap_or("")
            )));
        }
    }
    let width = header.split(',').count();
    lines
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            let fields: Vec<&str> = l.split(',').collect();
            if fields.len() != width {
                return Err(bad(format!(
                    "line {} has {} fields, the header {width}",
                    k + 2,
                    fields.len()
                )));
            }
            fields
                .iter()
                .zip(header.split(','))
                .map(|(f, name)| {
                    f.trim().parse::<f64>().map_err(|_| {
                        bad(format!("line {}: `{name}` is not a number: `{f}`", k + 2))
                    })
                })
                .collect()
        })
        .collect()
}

/// Field `k` of a row as an id, which must be a whole number in `u32`'s range.
fn id_at(r: &[f64], k: usize, what: &str) -> Result<u32, super::CgError> {
    let x = r[k];
    if x.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&x) {
        Ok(x as u32)
    } else {
        Err(super::CgError::Invalid(format!(
            "{what}: an id must be a whole number from 0 to {}, got {x}",
            u32::MAX
        )))
    }
}

fn vec_at(r: &[f64], k: usize) -> DVec3 {
    DVec3::new(r[k], r[k + 1], r[k + 2])
}

/// Reads the particle records of a file written by [`particles_csv`]; `what` names the file
/// in errors.
///
/// # Errors
/// [`super::CgError::Invalid`] naming the line and field of the first bad value.
pub fn read_particles_csv(text: &str, what: &str) -> Result<Vec<ParticleRecord>, super::CgError> {
    let old = text.lines().next().map(str::trim) == Some(PARTICLE_COLUMNS_NO_SPIN);
    let header = if old {
        PARTICLE_COLUMNS_NO_SPIN
    } else {
        PARTICLE_COLUMNS
    };
    rows(text, header, what)?
        .into_iter()
        .map(|r| {
            Ok(ParticleRecord {
                id: id_at(&r, 0, what)?,
                position: vec_at(&r, 1),
                velocity: vec_at(&r, 4),
                radius: r[7],
                mass: r[8],
                free: r[9] != 0.0,
                angular_velocity: if old { DVec3::NAN } else { vec_at(&r, 10) },
            })
        })
        .collect()
}

/// Reads the contact records of a file written by [`contacts_csv`]; `what` names the file
/// in errors.
///
/// # Errors
/// [`super::CgError::Invalid`] naming the line and field of the first bad value.
pub fn read_contacts_csv(text: &str, what: &str) -> Result<Vec<ContactRecord>, super::CgError> {
    rows(text, CONTACT_COLUMNS, what)?
        .into_iter()
        .map(|r| {
            Ok(ContactRecord {
                i: id_at(&r, 0, what)?,
                j: id_at(&r, 1, what)?,
                wall: r[2] != 0.0,
                overlap: r[3],
                centre_i: vec_at(&r, 4),
                branch: vec_at(&r, 7),
                point_i: vec_at(&r, 10),
                force_i: vec_at(&r, 13),
                centre_j: vec_at(&r, 16),
                point_j: vec_at(&r, 19),
                force_j: vec_at(&r, 22),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contact(i: u32) -> ContactRecord {
        let v = |k: f64| DVec3::new(k, -k / 3.0, 1e-300 * k);
        ContactRecord {
            i,
            j: i + 7,
            wall: i.is_multiple_of(2),
            overlap: -1.25e-5,
            centre_i: v(1.0),
            branch: v(0.1),
            point_i: v(0.7),
            force_i: v(std::f64::consts::PI),
            centre_j: v(2.0),
            point_j: v(0.3),
            force_j: v(-std::f64::consts::E),
        }
    }

    #[test]
    fn records_read_back_exactly() {
        let contacts: Vec<ContactRecord> = (0..5).map(contact).collect();
        let back = read_contacts_csv(&contacts_csv(&contacts), "c.csv").expect("read");
        assert_eq!(back, contacts);
        let particles = vec![ParticleRecord {
            id: 3,
            position: DVec3::new(0.1, 0.2, 1.0 / 3.0),
            velocity: DVec3::new(-1e-17, 0.0, 2.5),
            radius: 1.1e-3,
            mass: 1.0 / 7.0,
            free: false,
            angular_velocity: DVec3::new(3.0, -1.0 / 9.0, 0.0),
        }];
        let back = read_particles_csv(&particles_csv(&particles), "p.csv").expect("read");
        assert_eq!(back, particles);
        // A file without the angular velocity columns reads, with it unknown.
        let old = "id,x,y,z,vx,vy,vz,radius,mass,free\n3,1e-1,2e-1,0,0,0,0,1e-3,1e0,1\n";
        let back = read_particles_csv(old, "old.csv").expect("old format");
        assert!(back[0].angular_velocity.is_nan() && back[0].free);
    }

    #[test]
    fn bad_records_name_the_file_line_and_field() {
        let good = particles_csv(&[ParticleRecord {
            id: 0,
            position: DVec3::ZERO,
            velocity: DVec3::ZERO,
            radius: 1.0,
            mass: 1.0,
            free: true,
            angular_velocity: DVec3::ZERO,
        }]);
        let bad = good.replacen(",1e0,1e0,1", ",x,1e0,1", 1);
        let e = read_particles_csv(&bad, "p.csv")
            .expect_err("bad radius")
            .to_string();
        assert!(
            e.contains("p.csv") && e.contains("line 2") && e.contains("`radius`"),
            "{e}"
        );
        let e = read_particles_csv("id,x\n", "p.csv")
            .expect_err("header")
            .to_string();
        assert!(e.contains("header"), "{e}");
        let e = read_particles_csv(&good.replacen("\n0,", "\n-2,", 1), "p.csv")
            .expect_err("negative id")
            .to_string();
        assert!(e.contains("whole number"), "{e}");
    }
}
