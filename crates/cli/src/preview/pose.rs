//! The camera's pose as a scene file writes it, printed by the preview on `P` and on close.
//! Every scene format's syntax is one arm of [`format_pose`].

use glam::DVec3;

/// Where the camera is and where it looks, in the scene's world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// The eye, in scene units.
    pub eye: DVec3,
    /// The unit view direction.
    pub dir: DVec3,
    /// The world's up direction for flying (unit): `+z` for course files (the ray tracer's
    /// convention), the file camera's up for Mitsuba files (often `+y`).
    pub up: DVec3,
}

impl Pose {
    /// The pose of a scene's camera.
    pub fn of_camera(camera: &raytracer::scene::CameraSettings) -> Pose {
        Pose { eye: camera.eye, dir: camera.dir, up: camera.up.unwrap_or(DVec3::Z) }
    }

    /// Puts a scene's camera at this pose (its image's up kept at right angles to the view, for a
    /// camera that states one).
    pub fn apply(&self, camera: &mut raytracer::scene::CameraSettings) {
        camera.eye = self.eye;
        camera.dir = self.dir;
        if camera.up.is_some() {
            camera.up = (self.up - self.dir * self.up.dot(self.dir)).try_normalize().or(camera.up);
        }
    }
}

/// The scene language a pose is printed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseSyntax {
    /// The course scene language: `O=` and `N=` of the `camera` block.
    Course,
    /// Mitsuba 3's XML: a `<lookat>` element of the sensor's `to_world`.
    Mitsuba,
}

/// The lines that put the camera at `pose` in a scene file of `syntax`, to paste over the
/// file's own.
pub fn format_pose(pose: &Pose, syntax: PoseSyntax) -> String {
    match syntax {
        PoseSyntax::Course => {
            format!("camera\n    O= {}\n    N= {}", numbers(pose.eye), numbers(pose.dir))
        }
        PoseSyntax::Mitsuba => format!(
            "<lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>",
            commas(pose.eye),
            commas(pose.eye + pose.dir),
            commas(pose.up)
        ),
    }
}

/// The pose as scene-file lines under a comment of the file's syntax saying what it is: the
/// camera `when` (e.g. "now"), for the scene file `scene`.
pub fn pose_note(pose: &Pose, syntax: PoseSyntax, scene: &str, when: &str) -> String {
    let comment = match syntax {
        PoseSyntax::Course => "//",
        PoseSyntax::Mitsuba => "<!--",
    };
    let (block, end) = match syntax {
        PoseSyntax::Course => ("the camera block", ""),
        PoseSyntax::Mitsuba => ("the sensor's to_world", " -->"),
    };
    format!(
        "{comment} the preview's camera {when}, for {block} of {scene}:{end}\n{}",
        format_pose(pose, syntax)
    )
}

/// Three numbers separated by commas (Mitsuba's attribute lists), each as [`numbers`] writes
/// it.
fn commas(v: DVec3) -> String {
    numbers(v).replace(' ', ", ")
}

/// Three numbers separated by spaces, each as short as it can be and still read back as the
/// same 32-bit value (the fly camera's precision).
fn numbers(v: DVec3) -> String {
    let short = |x: f64| {
        let x = x as f32;
        // `-0` reads as 0 anyway.
        if x == 0.0 { "0".to_owned() } else { format!("{x}") }
    };
    format!("{} {} {}", short(v.x), short(v.y), short(v.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use raytracer::scene::{self, SourceFile};

    #[test]
    fn a_printed_pose_reads_back_as_the_camera() {
        let pose = Pose {
            eye: DVec3::new(-2.5, 1.25e-3, 0.5),
            dir: DVec3::new(0.6, 0.8, -0.0).normalize(),
            up: DVec3::Z,
        };
        let text = format_pose(&pose, PoseSyntax::Course);
        assert_eq!(text, "camera\n    O= -2.5 0.00125 0.5\n    N= 0.6 0.8 0");
        let file = format!("{text}\n    image_W= 8\n    image_H= 8\nend\n");
        let source = SourceFile::from_text("pose.txt", None, file);
        let parsed = scene::parse(&source).expect("the printed camera parses");
        let camera = &parsed.scene.camera;
        assert!((camera.eye - pose.eye).length() < 1e-6, "{:?}", camera.eye);
        assert!((camera.dir - pose.dir).length() < 1e-6, "{:?}", camera.dir);
    }

    #[test]
    fn a_pose_note_is_a_comment_then_the_camera_block() {
        let pose = Pose { eye: DVec3::new(1.0, 2.0, 3.0), dir: DVec3::Y, up: DVec3::Z };
        let note = pose_note(&pose, PoseSyntax::Course, "box.txt", "now");
        assert_eq!(
            note,
            "// the preview's camera now, for the camera block of box.txt:\ncamera\n    O= 1 2 3\n    N= 0 1 0"
        );
    }

    #[test]
    fn a_mitsuba_pose_is_a_lookat_that_reads_back() {
        let pose = Pose { eye: DVec3::new(278.0, 273.0, -800.0), dir: DVec3::Z, up: DVec3::Y };
        let text = format_pose(&pose, PoseSyntax::Mitsuba);
        assert_eq!(text, "<lookat origin=\"278, 273, -800\" target=\"278, 273, -799\" up=\"0, 1, 0\"/>");
        let file = format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"><transform name=\"to_world\">{text}</transform></sensor></scene>"
        );
        let doc = raytracer::scene::mitsuba::read_source(SourceFile::from_text("p.xml", None, file), &[])
            .expect("the printed lookat reads");
        let built = raytracer::scene::mitsuba::build(&doc).expect("builds");
        let camera = &built.scene.camera;
        assert!((camera.eye - pose.eye).length() < 1e-9 && (camera.dir - pose.dir).length() < 1e-9);
        assert_eq!(camera.up, Some(DVec3::Y));
        let note = pose_note(&pose, PoseSyntax::Mitsuba, "cbox.xml", "now");
        assert!(note.starts_with(
            "<!-- the preview's camera now, for the sensor's to_world of cbox.xml: -->\n<lookat"
        ));
    }
}
