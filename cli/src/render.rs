//! A small built-in renderer: orthographic splats of points, coloured by a colour map over a
//! scalar field (or one flat colour), lit by a fixed directional light when normals are given,
//! with a depth buffer; PNG output. Enough to see noise before smoothing and sharp edges after.
//!
//! Without normals the colour is flat apart from a mild depth cue (farther points darker),
//! so that shape still reads.

use nbhd::io::PointCloud;
use std::path::Path;

/// Colour maps over `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColorMap {
    /// Perceptually uniform, dark blue to yellow (matplotlib's default).
    #[default]
    Viridis,
    /// Google's rainbow-like map with high contrast, dark blue through green to dark red.
    Turbo,
    /// Black to white.
    Gray,
    /// Pale grey-blue through yellow and orange to dark red: flat regions stay light, so the
    /// light still shows the shape, and high values stand out.
    Heat,
}

impl ColorMap {
    /// The colour at `t` (clamped to `[0, 1]`).
    pub fn color(self, t: f64) -> [u8; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let c = match self {
            ColorMap::Viridis => {
                const STOPS: [[f64; 3]; 9] = [
                    [68.0, 1.0, 84.0],
                    [71.0, 44.0, 122.0],
                    [59.0, 81.0, 139.0],
                    [44.0, 113.0, 142.0],
                    [33.0, 144.0, 141.0],
                    [39.0, 173.0, 129.0],
                    [92.0, 200.0, 99.0],
                    [170.0, 220.0, 50.0],
                    [253.0, 231.0, 37.0],
                ];
                let x = t * 8.0;
                let i = (x.floor() as usize).min(7);
                let f = x - i as f64;
                let (a, b) = (STOPS[i], STOPS[i + 1]);
                [0, 1, 2].map(|j| (a[j] + (b[j] - a[j]) * f) / 255.0)
            }
            ColorMap::Turbo => {
                // Polynomial approximation of Turbo (A. Mikhailov, Google, 2019).
                let p = |c: [f64; 6]| {
                    c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))))
                };
                [
                    p([0.1357, 4.6154, -42.6603, 132.1311, -152.9424, 59.2864]),
                    p([0.0914, 2.1942, 4.8430, -14.1850, 4.2773, 2.8296]),
                    p([0.1067, 12.6419, -60.5820, 110.3628, -89.9031, 27.3482]),
                ]
            }
            ColorMap::Gray => [t, t, t],
            ColorMap::Heat => {
                const STOPS: [[f64; 3]; 5] = [
                    [225.0, 232.0, 245.0],
                    [245.0, 225.0, 140.0],
                    [245.0, 150.0, 50.0],
                    [215.0, 50.0, 30.0],
                    [140.0, 10.0, 30.0],
                ];
                let x = t * 4.0;
                let i = (x.floor() as usize).min(3);
                let f = x - i as f64;
                let (a, b) = (STOPS[i], STOPS[i + 1]);
                [0, 1, 2].map(|j| (a[j] + (b[j] - a[j]) * f) / 255.0)
            }
        };
        c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
    }
}

/// How to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Direction the camera looks in (from the eye into the scene), world coordinates.
    pub view: [f64; 3],
    /// World direction that appears upwards in the picture.
    pub up: [f64; 3],
    /// Splat radius in pixels; `None` picks one from the point density.
    pub point_radius: Option<f64>,
    /// Colour map for scalar values.
    pub colormap: ColorMap,
    /// Scalar values mapped to the ends of the colour map; `None` takes the finite min/max.
    pub range: Option<(f64, f64)>,
    /// Colour of points when no scalar field is drawn.
    pub flat_color: [u8; 3],
    /// Background colour.
    pub background: [u8; 3],
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 800,
            height: 600,
            view: [-1.0, -1.0, -1.0],
            up: [0.0, 1.0, 0.0],
            point_radius: None,
            colormap: ColorMap::Viridis,
            range: None,
            flat_color: [200, 200, 210],
            background: [255, 255, 255],
        }
    }
}

/// An RGB picture.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGB pixels, top row first.
    pub pixels: Vec<[u8; 3]>,
}

impl Image {
    /// The pixel at column `x`, row `y` (row 0 at the top).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Number of pixels that differ from `background`.
    pub fn coverage(&self, background: [u8; 3]) -> usize {
        self.pixels.iter().filter(|&&p| p != background).count()
    }

    /// The picture as PNG bytes.
    pub fn encode_png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header()?;
            w.write_image_data(self.pixels.as_flattened())?;
        }
        Ok(out)
    }

    /// Writes the picture as a PNG file.
    pub fn save_png(&self, path: &Path) -> std::io::Result<()> {
        let bytes = self.encode_png().map_err(std::io::Error::other)?;
        std::fs::write(path, bytes)
    }
}

fn normalize(v: [f64; 3]) -> Option<[f64; 3]> {
    let l = dot(v, v).sqrt();
    (l > 1e-300 && l.is_finite()).then(|| v.map(|c| c / l))
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Camera basis: right, up, forward.
fn basis(view: [f64; 3], up: [f64; 3]) -> [[f64; 3]; 3] {
    let f = normalize(view).unwrap_or([0.0, 0.0, -1.0]);
    let r = normalize(cross(f, up))
        .or_else(|| normalize(cross(f, [0.0, 0.0, 1.0])))
        .or_else(|| normalize(cross(f, [1.0, 0.0, 0.0])))
        .expect("some axis is not parallel to the view");
    let u = cross(r, f);
    [r, u, f]
}

/// What colours the points.
#[derive(Clone, Copy, Debug)]
pub enum Paint<'a> {
    /// [`RenderOptions::flat_color`] for all.
    Flat,
    /// One value per point, through the colour map; NaN values in grey.
    Scalar(&'a [f64]),
    /// One colour per point (e.g. a scan's camera colours).
    Rgb(&'a [[u8; 3]]),
}

/// Draws points. `normals` (one per point) switch on the light; `paint` colours them.
/// Non-finite points are left out. Same input, same picture.
pub fn render(
    positions: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
    paint: Paint<'_>,
    opts: &RenderOptions,
) -> Image {
    let (w, h) = (opts.width.max(1), opts.height.max(1));
    let mut img = Image {
        width: w,
        height: h,
        pixels: vec![opts.background; (w * h) as usize],
    };
    let [r, u, f] = basis(opts.view, opts.up);
    // Project the finite points.
    let proj: Vec<(usize, [f64; 3])> = positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.iter().all(|c| c.is_finite()))
        .map(|(i, &p)| (i, [dot(p, r), dot(p, u), dot(p, f)]))
        .collect();
    if proj.is_empty() {
        return img;
    }
    let frame = Frame::fit(&proj, w, h);
    let radius = opts
        .point_radius
        .unwrap_or_else(|| frame.splat_radius(proj.len()));
    let colors = Colors::new(paint, &proj, opts);
    // Light from the upper left, behind the viewer; two-sided (scan normals are often
    // unoriented).
    let light = normalize([
        -0.45 * r[0] + 0.6 * u[0] - f[0],
        -0.45 * r[1] + 0.6 * u[1] - f[1],
        -0.45 * r[2] + 0.6 * u[2] - f[2],
    ])
    .unwrap();
    let depth_span = (frame.hi[2] - frame.lo[2]).max(1e-300);
    let mut zbuf = vec![f64::INFINITY; (w * h) as usize];
    for &(i, q) in &proj {
        let shade = match normals.and_then(|n| normalize(n[i])) {
            Some(n) => 0.22 + 0.78 * dot(n, light).abs(),
            None => 1.0 - 0.45 * (q[2] - frame.lo[2]) / depth_span,
        };
        let color = colors
            .of(i)
            .map(|c| (c as f64 * shade).round().clamp(0.0, 255.0) as u8);
        splat(&mut img, &mut zbuf, &frame, q, radius, color);
    }
    img
}

/// Where the projected points land: their bounding box in camera coordinates, and the scale
/// and centre that fit it into the picture with a margin, the same scale on both axes.
struct Frame {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Extent of the box across and up the picture (at least 1e-300).
    extent: (f64, f64),
    /// Pixels per unit.
    scale: f64,
    /// Centre of the box across and up.
    centre: (f64, f64),
    /// Picture size in pixels.
    size: (u32, u32),
}

impl Frame {
    fn fit(proj: &[(usize, [f64; 3])], w: u32, h: u32) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (_, q) in proj {
            for j in 0..3 {
                lo[j] = lo[j].min(q[j]);
                hi[j] = hi[j].max(q[j]);
            }
        }
        let margin = 0.06;
        let (aw, ah) = (
            w as f64 * (1.0 - 2.0 * margin),
            h as f64 * (1.0 - 2.0 * margin),
        );
        let (ex, ey) = ((hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300));
        let scale = if hi[0] - lo[0] == 0.0 && hi[1] - lo[1] == 0.0 {
            1.0
        } else {
            (aw / ex).min(ah / ey)
        };
        Self {
            lo,
            hi,
            extent: (ex, ey),
            scale,
            centre: ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0),
            size: (w, h),
        }
    }

    /// A splat radius in pixels from the point density: about half the `n` points face the
    /// camera; together they cover the projected area.
    fn splat_radius(&self, n: usize) -> f64 {
        let (ex, ey) = self.extent;
        let area = (ex * self.scale).max(1.0) * (ey * self.scale).max(1.0);
        let per_point = area / (n as f64 / 2.0).max(1.0);
        (per_point / std::f64::consts::PI).sqrt().clamp(1.0, 12.0) * 2.0
    }

    /// The picture position (x right, y down, in pixels) of a projected point.
    fn pixel(&self, q: [f64; 3]) -> (f64, f64) {
        let (w, h) = self.size;
        (
            (q[0] - self.centre.0) * self.scale + w as f64 / 2.0,
            h as f64 / 2.0 - (q[1] - self.centre.1) * self.scale,
        )
    }
}

/// The unlit colour of each point.
struct Colors<'a> {
    paint: Paint<'a>,
    /// Scalar values at the two ends of the colour map (scalar paint only).
    range: Option<(f64, f64)>,
    colormap: ColorMap,
    flat: [u8; 3],
}

impl<'a> Colors<'a> {
    /// The colours of `paint`; a scalar range not given in `opts` is the finite min/max of the
    /// drawn points.
    fn new(paint: Paint<'a>, proj: &[(usize, [f64; 3])], opts: &RenderOptions) -> Self {
        let range = match paint {
            Paint::Scalar(s) => Some(opts.range.unwrap_or_else(|| {
                let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
                for &(i, _) in proj {
                    if s[i].is_finite() {
                        a = a.min(s[i]);
                        b = b.max(s[i]);
                    }
                }
                if a > b {
                    (0.0, 1.0)
                } else {
                    (a, b)
                }
            })),
            _ => None,
        };
        Self {
            paint,
            range,
            colormap: opts.colormap,
            flat: opts.flat_color,
        }
    }

    /// The colour of point `i`: NaN scalars grey, a constant scalar the map's middle.
    fn of(&self, i: usize) -> [u8; 3] {
        match (self.paint, self.range) {
            (Paint::Scalar(s), Some((a, b))) => {
                if s[i].is_nan() {
                    [150, 150, 150]
                } else if b > a {
                    self.colormap.color((s[i] - a) / (b - a))
                } else {
                    self.colormap.color(0.5)
                }
            }
            (Paint::Rgb(c), _) => c[i],
            _ => self.flat,
        }
    }
}

/// Draws one point as a small sphere of `radius` pixels (its centre nearer than its rim)
/// where it is nearer than what the depth buffer holds.
fn splat(
    img: &mut Image,
    zbuf: &mut [f64],
    frame: &Frame,
    q: [f64; 3],
    radius: f64,
    color: [u8; 3],
) {
    let (w, h) = frame.size;
    let rr = radius * radius;
    let ri = radius.ceil() as i64;
    let (px, py) = frame.pixel(q);
    let (x0, y0) = (px.floor() as i64, py.floor() as i64);
    for dy in -ri..=ri {
        let y = y0 + dy;
        if y < 0 || y >= h as i64 {
            continue;
        }
        for dx in -ri..=ri {
            let x = x0 + dx;
            if x < 0 || x >= w as i64 {
                continue;
            }
            let (ddx, ddy) = (x as f64 + 0.5 - px, y as f64 + 0.5 - py);
            let d2 = ddx * ddx + ddy * ddy;
            if d2 > rr {
                continue;
            }
            let z = q[2] - (rr - d2).sqrt() / frame.scale;
            let k = (y as u32 * w + x as u32) as usize;
            if z < zbuf[k] {
                zbuf[k] = z;
                img.pixels[k] = color;
            }
        }
    }
}

/// Draws a cloud, coloured by the scalar field `color_by`, by a coordinate (`x`, `y`, `z`), or
/// by the cloud's own colours (`rgb`: a packed `rgb`/`rgba` field or `red green blue`).
pub fn render_cloud(
    cloud: &PointCloud,
    color_by: Option<&str>,
    opts: &RenderOptions,
) -> crate::error::Result<Image> {
    let coord: Vec<f64>;
    let colors: Vec<[u8; 3]>;
    let paint = match color_by {
        None => Paint::Flat,
        Some(name @ ("x" | "y" | "z")) => {
            let j = ["x", "y", "z"].iter().position(|c| *c == name).unwrap();
            coord = cloud.positions.iter().map(|p| p[j]).collect();
            Paint::Scalar(&coord)
        }
        Some("rgb" | "rgba" | "color") => {
            colors = cloud
                .colors()
                .ok_or("the cloud has no colours (no rgb, rgba or red/green/blue field)")?;
            Paint::Rgb(&colors)
        }
        Some(name) => Paint::Scalar(cloud.scalar(name).ok_or_else(|| {
            let names: Vec<&str> = cloud.scalars.iter().map(|s| s.name.as_str()).collect();
            format!(
                "no scalar field '{name}' (the file has: x y z{}{})",
                if names.is_empty() { "" } else { " " },
                names.join(" ")
            )
        })?),
    };
    Ok(render(
        &cloud.positions,
        cloud.normals.as_deref(),
        paint,
        opts,
    ))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// `n` points spread evenly over the unit sphere (Fibonacci lattice), with normals.
    pub fn sphere(n: usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let p: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - y * y).sqrt();
                let t = golden * i as f64;
                [r * t.cos(), y, r * t.sin()]
            })
            .collect();
        (p.clone(), p)
    }

    /// Points on the surface of the cube [-1, 1]^3, `m` x `m` per face, with normals.
    pub fn cube(m: usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let mut p = Vec::new();
        let mut n = Vec::new();
        for axis in 0..3 {
            for side in [-1.0, 1.0] {
                for a in 0..m {
                    for b in 0..m {
                        let s = -1.0 + 2.0 * (a as f64 + 0.5) / m as f64;
                        let t = -1.0 + 2.0 * (b as f64 + 0.5) / m as f64;
                        let mut q = [0.0; 3];
                        q[axis] = side;
                        q[(axis + 1) % 3] = s;
                        q[(axis + 2) % 3] = t;
                        let mut nn = [0.0; 3];
                        nn[axis] = side;
                        p.push(q);
                        n.push(nn);
                    }
                }
            }
        }
        (p, n)
    }

    #[test]
    fn image_has_the_requested_size_and_png_decodes() {
        let (p, n) = sphere(2000);
        let opts = RenderOptions {
            width: 320,
            height: 200,
            ..Default::default()
        };
        let img = render(&p, Some(&n), Paint::Flat, &opts);
        assert_eq!((img.width, img.height), (320, 200));
        assert_eq!(img.pixels.len(), 320 * 200);
        let bytes = img.encode_png().unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = dec.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (320, 200));
    }

    #[test]
    fn sphere_covers_a_disc() {
        let (p, n) = sphere(5000);
        let opts = RenderOptions {
            width: 200,
            height: 200,
            ..Default::default()
        };
        let img = render(&p, Some(&n), Paint::Flat, &opts);
        // The sphere fills a disc of diameter 88% of the side: pi/4 * 0.88^2 = 61% of the
        // pixels, with splat rims a little more. No holes in the middle.
        let cov = img.coverage(opts.background) as f64 / (200.0 * 200.0);
        assert!((0.55..0.70).contains(&cov), "coverage {cov}");
        assert_ne!(img.pixel(100, 100), opts.background);
        assert_eq!(img.pixel(2, 2), opts.background);
        // Lit from the upper left: that side is brighter than the lower right.
        let lum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
        assert!(lum(img.pixel(70, 70)) > lum(img.pixel(130, 130)));
    }

    #[test]
    fn rendering_is_deterministic_and_colours_follow_the_scalar() {
        let (p, _) = cube(30);
        let s: Vec<f64> = p.iter().map(|q| q[1]).collect();
        let opts = RenderOptions {
            width: 160,
            height: 120,
            colormap: ColorMap::Turbo,
            ..Default::default()
        };
        let a = render(&p, None, Paint::Scalar(&s), &opts);
        let b = render(&p, None, Paint::Scalar(&s), &opts);
        assert_eq!(a, b);
        assert!(a.coverage(opts.background) > 160 * 120 / 4);
        // Flat colour: every covered pixel is a shade of the flat colour.
        let flat = render(&p, None, Paint::Flat, &opts);
        assert_ne!(flat, a);
        // Own colours: a red cloud has only reddish pixels.
        let red = vec![[200, 0, 0]; p.len()];
        let r = render(&p, None, Paint::Rgb(&red), &opts);
        assert!(r
            .pixels
            .iter()
            .all(|&c| c == opts.background || (c[1] == 0 && c[2] == 0 && c[0] > 0)));
    }

    #[test]
    fn empty_and_all_nan_input_give_a_blank_picture() {
        let opts = RenderOptions::default();
        assert_eq!(
            render(&[], None, Paint::Flat, &opts).coverage(opts.background),
            0
        );
        let p = vec![[f64::NAN; 3]; 4];
        assert_eq!(
            render(&p, None, Paint::Flat, &opts).coverage(opts.background),
            0
        );
        // One point still shows.
        assert!(render(&[[1.0, 2.0, 3.0]], None, Paint::Flat, &opts).coverage(opts.background) > 0);
    }

    #[test]
    fn colour_maps_run_from_dark_to_light() {
        for m in [ColorMap::Viridis, ColorMap::Turbo, ColorMap::Gray] {
            let lum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
            assert!(lum(m.color(0.0)) < lum(m.color(0.6)), "{m:?}");
        }
        assert_eq!(ColorMap::Viridis.color(0.0), [68, 1, 84]);
        assert_eq!(ColorMap::Viridis.color(1.0), [253, 231, 37]);
        // Heat runs the other way: light where flat, dark red at the hot end.
        let lum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
        let heat: Vec<u32> = (0..=10)
            .map(|i| lum(ColorMap::Heat.color(i as f64 / 10.0)))
            .collect();
        assert!(heat[0] > heat[10] + 300, "{heat:?}");
        let hot = ColorMap::Heat.color(1.0);
        assert!(hot[0] > 2 * hot[1] && hot[0] > 2 * hot[2], "{hot:?}");
    }

    #[test]
    #[ignore = "writes pictures to /tmp for a person to look at"]
    fn look() {
        let (p, n) = sphere(20000);
        let s: Vec<f64> = p.iter().map(|q| q[1]).collect();
        render(&p, Some(&n), Paint::Scalar(&s), &RenderOptions::default())
            .save_png(Path::new("/tmp/nbhd-sphere.png"))
            .unwrap();
        let (p, n) = cube(80);
        render(&p, Some(&n), Paint::Flat, &RenderOptions::default())
            .save_png(Path::new("/tmp/nbhd-cube.png"))
            .unwrap();
        render(&p, None, Paint::Flat, &RenderOptions::default())
            .save_png(Path::new("/tmp/nbhd-cube-flat.png"))
            .unwrap();
    }
}
