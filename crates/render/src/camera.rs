//! The perspective camera and its framing of an object's bounding sphere.
//!
//! ```text
//!              camera
//!               *  .
//!              /  \    .   elevation e above the horizontal plane
//!   half fov  / a  \       .
//!            /      \          .
//!           (   r    )------------- centre c, distance d = k r
//! ```
//!
//! The camera sits at `c + d (0, sin e, cos e)` (before the turntable rotation), looks at the
//! centre with +y up, and the sphere of radius `r` is seen under the half-angle
//! `a = asin(r / d)`. The field of view is chosen so that the sphere's image has a diameter of
//! `fill` times the shorter side of the frame: `tan(fov / 2) = tan(a) / fill`.

use crate::{RenderError, Result};
use glam::{Mat4, Vec3};
use rmt_mesh::Mesh;

/// A sphere that contains every vertex of a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// The centre of the axis-aligned bounding box.
    pub center: Vec3,
    /// The largest distance from the centre to a vertex.
    pub radius: f32,
}

impl BoundingSphere {
    /// The sphere around the bounding box's centre through the farthest vertex.
    ///
    /// Errors when the mesh has no vertex, a non-finite coordinate, or all vertices coincide.
    pub fn of_mesh(mesh: &Mesh) -> Result<Self> {
        let first = mesh
            .positions
            .first()
            .ok_or_else(|| RenderError::InvalidMesh("the mesh has no vertices".into()))?;
        let (mut lo, mut hi) = (Vec3::from(*first), Vec3::from(*first));
        for (i, p) in mesh.positions.iter().enumerate() {
            let p = Vec3::from(*p);
            if !p.is_finite() {
                return Err(RenderError::InvalidMesh(format!(
                    "vertex {i} has a non-finite position {p:?}"
                )));
            }
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let center = (lo + hi) * 0.5;
        let radius = mesh
            .positions
            .iter()
            .map(|p| Vec3::from(*p).distance(center))
            .fold(0.0f32, f32::max);
        if radius <= 0.0 || !radius.is_finite() {
            return Err(RenderError::InvalidMesh(format!(
                "the mesh has no extent (bounding radius {radius})"
            )));
        }
        Ok(Self { center, radius })
    }
}

/// A perspective camera fixed for a whole turntable.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// World to camera space (camera looks down -z, +y up).
    pub view: Mat4,
    /// Camera to clip space.
    pub projection: Mat4,
    /// Vertical field of view in radians.
    pub fov_y: f32,
    /// Distance from the eye to the sphere's centre.
    pub distance: f32,
}

impl Camera {
    /// The camera that frames `sphere` as described in the module documentation.
    ///
    /// `elevation_degrees` in -89..=89, `distance_radii` > 1 (the eye outside the sphere),
    /// `fill` in (0, 1] (the sphere's image stays inside the frame), `aspect` = width / height.
    pub fn framing(
        sphere: BoundingSphere,
        elevation_degrees: f32,
        distance_radii: f32,
        fill: f32,
        aspect: f32,
    ) -> Self {
        let distance = sphere.radius * distance_radii;
        let e = elevation_degrees.to_radians();
        let eye = sphere.center + distance * Vec3::new(0.0, e.sin(), e.cos());
        let view = Mat4::look_at_rh(eye, sphere.center, Vec3::Y);
        let half_angle = (1.0 / distance_radii).asin();
        // The shorter side of the frame decides: with a wide frame the vertical fov fits the
        // sphere, with a tall frame the horizontal one does.
        let tan_half_short = half_angle.tan() / fill;
        let tan_half_y = if aspect >= 1.0 {
            tan_half_short
        } else {
            tan_half_short / aspect
        };
        let fov_y = 2.0 * tan_half_y.atan();
        // Near and far planes only bound the clip volume; depth testing uses 1/w, so their ratio
        // does not cost precision.
        let near = (distance - sphere.radius) * 0.5;
        let far = distance + sphere.radius * 2.0;
        let projection = Mat4::perspective_rh(fov_y, aspect, near, far);
        Self {
            view,
            projection,
            fov_y,
            distance,
        }
    }

    /// The radius, in pixels, of the image of a sphere of radius `r` centred on the optical axis
    /// at distance `distance`, for a frame `height` pixels tall.
    pub fn projected_radius_pixels(&self, r: f32, height: u32) -> f32 {
        let half_angle = (r / self.distance).asin();
        half_angle.tan() / (self.fov_y * 0.5).tan() * height as f32 * 0.5
    }
}

/// The model matrix of a turntable: the object turned by `angle_radians` about the vertical
/// (+y) axis through `center` (its bounding sphere's centre, so the sphere stays in place).
pub fn turntable_model(center: Vec3, angle_radians: f32) -> Mat4 {
    Mat4::from_translation(center)
        * Mat4::from_rotation_y(angle_radians)
        * Mat4::from_translation(-center)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_makes_the_sphere_fill_the_requested_share() {
        let sphere = BoundingSphere {
            center: Vec3::new(1.0, 2.0, 3.0),
            radius: 2.5,
        };
        for (fill, dist) in [(0.9, 3.0), (0.5, 10.0), (1.0, 1.5)] {
            let cam = Camera::framing(sphere, 20.0, dist, fill, 1.0);
            let r = cam.projected_radius_pixels(sphere.radius, 200);
            assert!((r - fill * 100.0).abs() < 1e-2, "fill {fill}: radius {r}");
        }
    }

    #[test]
    fn centre_projects_to_the_middle_of_the_frame() {
        let sphere = BoundingSphere {
            center: Vec3::new(-4.0, 1.0, 0.5),
            radius: 1.0,
        };
        let cam = Camera::framing(sphere, 35.0, 4.0, 0.8, 1.5);
        let clip = cam.projection * cam.view * sphere.center.extend(1.0);
        assert!((clip.x / clip.w).abs() < 1e-5 && (clip.y / clip.w).abs() < 1e-5);
    }

    #[test]
    fn bounding_sphere_rejects_empty_and_non_finite_meshes() {
        assert!(BoundingSphere::of_mesh(&Mesh::default()).is_err());
        let bad = Mesh::from_triangles(vec![[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0]], vec![]);
        let msg = BoundingSphere::of_mesh(&bad).unwrap_err().to_string();
        assert!(msg.contains("vertex 1"), "{msg}");
        let point = Mesh::from_triangles(vec![[1.0, 1.0, 1.0]; 3], vec![0, 1, 2]);
        assert!(BoundingSphere::of_mesh(&point).is_err());
    }
}
