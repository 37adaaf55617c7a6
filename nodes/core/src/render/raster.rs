//! Triangles in, pixels out: the frame buffers and the one routine that fills them.
//!
//! Triangles arrive in the camera's optical frame (metres, +z forward). Each is culled if it
//! faces away, clipped against the near plane, projected, and filled by edge functions over its
//! bounding box, pixel centres at half-integers. Depth is tested on 1/z, which is linear in
//! screen space, so the depth written is exact for planar faces. One colour per triangle
//! (flat shading): cheap, and the facets make depth and orientation easy to read.

use nalgebra::{Point3, Vector3};

/// The near clipping plane (m): closer surfaces are cut away. The wrist camera's nearest
/// sight, the gripper fingers, is several centimetres off.
pub const NEAR: f32 = 0.01;

/// What a pixel shows, by the kind of thing drawn there last.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum SceneClass {
    /// Nothing: the sky.
    Background = 0,
    /// The ground plane.
    Ground = 1,
    /// Bins, shelf, trash can, obstacles.
    Arena = 2,
    /// The arm, its pedestal and the gripper.
    Robot = 3,
    /// The manipulated object.
    Object = 4,
}

/// One rendered image: colour, depth and what each pixel shows, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Width (pixels).
    pub width: u32,
    /// Height (pixels).
    pub height: u32,
    /// RGB8, 3 bytes per pixel, row-major from the top-left pixel (ROS `rgb8`).
    pub rgb: Vec<u8>,
    /// Depth along the optical axis (m) per pixel, `+∞` where nothing was drawn (REP 117/118).
    pub depth: Vec<f32>,
    /// What each pixel shows. The goal marker is see-through: it tints colour only.
    pub classes: Vec<SceneClass>,
}

/// The sky's colour.
pub const BACKGROUND: [u8; 3] = [205, 214, 228];

impl Frame {
    /// An empty frame: all sky, infinitely far.
    pub fn new(width: u32, height: u32) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            rgb: BACKGROUND.repeat(n),
            depth: vec![f32::INFINITY; n],
            classes: vec![SceneClass::Background; n],
        }
    }

    /// The colour at column `x`, row `y`.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * self.index(x, y);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// The depth (m) at column `x`, row `y`.
    pub fn depth_at(&self, x: u32, y: u32) -> f32 {
        self.depth[self.index(x, y)]
    }

    /// What column `x`, row `y` shows.
    pub fn class_at(&self, x: u32, y: u32) -> SceneClass {
        self.classes[self.index(x, y)]
    }

    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) is outside the frame"
        );
        y as usize * self.width as usize + x as usize
    }
}

/// How a solid's triangles are painted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Paint {
    /// Base colour, 0–1 per channel.
    pub colour: [f32; 3],
    /// The class its pixels get.
    pub class: SceneClass,
    /// `Some(alpha)` for a see-through solid: blended over what is there, writing neither depth
    /// nor class.
    pub alpha: Option<f32>,
}

/// Lighting and projection shared by every triangle of a frame.
pub(crate) struct View {
    /// Unit vector toward the key light, in the optical frame.
    pub light: Vector3<f32>,
    /// Focal length (pixels).
    pub focal: f32,
    /// Principal point (pixels).
    pub centre: (f32, f32),
}

/// Shade weights: ambient, the key light from above, and a headlight so faces turned to the
/// camera never go black.
const AMBIENT: f32 = 0.25;
const KEY: f32 = 0.5;
const HEADLIGHT: f32 = 0.35;

/// Draws one triangle (optical frame) into `frame`, whose depth buffer holds 1/z while
/// drawing (0 = nothing yet).
pub(crate) fn draw_triangle(
    frame: &mut Frame,
    view: &View,
    corners: [Point3<f32>; 3],
    paint: &Paint,
) {
    let [a, b, c] = corners;
    let normal = (b - a).cross(&(c - a));
    // Facing away (or edge-on): the camera sits at the origin.
    let facing = -normal.dot(&a.coords);
    if facing <= 0.0 {
        return;
    }
    let length = normal.norm();
    let n = normal / length;
    let headlight = facing / (length * a.coords.norm());
    let shade = AMBIENT + KEY * n.dot(&view.light).max(0.0) + HEADLIGHT * headlight;
    let colour = paint
        .colour
        .map(|c| (c * shade.min(1.0) * 255.0).round().clamp(0.0, 255.0));

    // Near-plane clipping (Sutherland–Hodgman against one plane) gives a convex polygon of up
    // to four corners, filled as a fan.
    let mut polygon: [Point3<f32>; 4] = [Point3::origin(); 4];
    let mut count = 0;
    for i in 0..3 {
        let (p, q) = (corners[i], corners[(i + 1) % 3]);
        let (p_in, q_in) = (p.z >= NEAR, q.z >= NEAR);
        if p_in {
            polygon[count] = p;
            count += 1;
        }
        if p_in != q_in {
            let t = (NEAR - p.z) / (q.z - p.z);
            polygon[count] = p + (q - p) * t;
            count += 1;
        }
    }
    if count < 3 {
        return;
    }
    let screen = polygon.map(|p| {
        let inv_z = 1.0 / p.z;
        [
            view.focal * p.x * inv_z + view.centre.0,
            view.focal * p.y * inv_z + view.centre.1,
            inv_z,
        ]
    });
    for k in 1..count - 1 {
        fill(frame, [screen[0], screen[k], screen[k + 1]], colour, paint);
    }
}

/// Fills a projected triangle whose corners are `[u, v, 1/z]`.
fn fill(frame: &mut Frame, mut corners: [[f32; 3]; 3], colour: [f32; 3], paint: &Paint) {
    let edge = |a: [f32; 3], b: [f32; 3], x: f32, y: f32| {
        (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])
    };
    let mut area = edge(corners[0], corners[1], corners[2][0], corners[2][1]);
    if area < 0.0 {
        corners.swap(1, 2);
        area = -area;
    }
    if area < 1e-12 {
        return;
    }
    let [p0, p1, p2] = corners;
    let (w, h) = (frame.width as f32, frame.height as f32);
    let min_x = p0[0].min(p1[0]).min(p2[0]).floor().max(0.0);
    let max_x = p0[0].max(p1[0]).max(p2[0]).ceil().min(w);
    let min_y = p0[1].min(p1[1]).min(p2[1]).floor().max(0.0);
    let max_y = p0[1].max(p1[1]).max(p2[1]).ceil().min(h);
    if min_x >= max_x || min_y >= max_y {
        return;
    }
    let (x0, x1) = (min_x as usize, max_x as usize);
    let (y0, y1) = (min_y as usize, max_y as usize);
    // Edge functions at the first pixel centre, and how they change per pixel step.
    let (sx, sy) = (min_x + 0.5, min_y + 0.5);
    let mut row = [
        edge(p1, p2, sx, sy),
        edge(p2, p0, sx, sy),
        edge(p0, p1, sx, sy),
    ];
    let step_x = [p1[1] - p2[1], p2[1] - p0[1], p0[1] - p1[1]];
    let step_y = [p2[0] - p1[0], p0[0] - p2[0], p1[0] - p0[0]];
    let inv_area = 1.0 / area;
    let z = [p0[2] * inv_area, p1[2] * inv_area, p2[2] * inv_area];
    let rgb = colour.map(|c| c as u8);
    let width = frame.width as usize;
    for y in y0..y1 {
        let mut e = row;
        for x in x0..x1 {
            if e[0] >= 0.0 && e[1] >= 0.0 && e[2] >= 0.0 {
                let inv_z = e[0] * z[0] + e[1] * z[1] + e[2] * z[2];
                let i = y * width + x;
                if inv_z > frame.depth[i] {
                    let px = &mut frame.rgb[3 * i..3 * i + 3];
                    match paint.alpha {
                        None => {
                            px.copy_from_slice(&rgb);
                            frame.depth[i] = inv_z;
                            frame.classes[i] = paint.class;
                        }
                        Some(alpha) => {
                            for (p, c) in px.iter_mut().zip(colour) {
                                *p = (*p as f32 * (1.0 - alpha) + c * alpha).round() as u8;
                            }
                        }
                    }
                }
            }
            e[0] += step_x[0];
            e[1] += step_x[1];
            e[2] += step_x[2];
        }
        row[0] += step_y[0];
        row[1] += step_y[1];
        row[2] += step_y[2];
    }
}
