//! The heat-map renderer on meshes whose picture is known: image size, where the body
//! lands, which way is up, which surface the z-buffer keeps, and a PNG that decodes.

use desal_mesh::TriMesh;
use desal_mesh::math::Vec3;
use desal_viz::render::{BAR_PANEL_WIDTH, TITLE_HEIGHT};
use desal_viz::{
    Direction, RenderConfig, Scalar, VizError, colormap, encode_png, render_heatmap, resolve_frame,
};

const WHITE: [u8; 4] = [255, 255, 255, 255];

/// An axis-aligned box `[-w/2, w/2] × [0, h] × [-d/2, d/2]` (12 triangles).
fn cuboid(w: f64, h: f64, d: f64) -> TriMesh {
    let mut positions = Vec::new();
    for &x in &[-w / 2.0, w / 2.0] {
        for &y in &[0.0, h] {
            for &z in &[-d / 2.0, d / 2.0] {
                positions.push(Vec3::new(x, y, z));
            }
        }
    }
    // Vertex index = 4·[x high] + 2·[y high] + [z high].
    let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    let faces = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    TriMesh { positions, faces }
}

/// A tall box (y up, thin in z) fills a known rectangle of the left view, and nothing
/// outside it is drawn.
#[test]
fn a_box_lands_in_the_expected_rectangle() {
    let mesh = cuboid(1.0, 2.0, 0.2);
    let heights: Vec<f64> = mesh.positions.iter().map(|p| p.y).collect();
    let config = RenderConfig::default();
    let image = render_heatmap(&mesh, Scalar::PerVertex(&heights), &config).unwrap();
    assert_eq!((image.width, image.height), (2 * 320 + BAR_PANEL_WIDTH, TITLE_HEIGHT + 600));

    // Scale: min(0.9 · 320 / 1, 0.9 · 600 / 2) = 270 px per unit, centred in the view:
    // x in [160 − 135, 160 + 135], y in [328 − 270, 328 + 270].
    let (left, right, top, bottom) = (25, 295, 58, 598);
    for y in TITLE_HEIGHT + 20..TITLE_HEIGHT + 600 {
        for x in 0..320 {
            let inside = x > left + 1 && x < right - 1 && y > top + 1 && y < bottom - 1;
            let outside = x < left - 1 || x > right + 1 || y < top - 1 || y > bottom + 1;
            let drawn = image.get(x, y) != WHITE;
            assert!(!inside || drawn, "pixel ({x}, {y}) inside the box is background");
            assert!(!outside || !drawn, "pixel ({x}, {y}) outside the box is drawn");
        }
    }
    // Up is up: the top of the box (scalar 2) is yellow, the bottom (scalar 0) purple.
    let top_px = image.get(160, top + 4);
    let bottom_px = image.get(160, bottom - 4);
    assert!(top_px[1] > 150 && top_px[0] > 150, "{top_px:?}");
    assert!(bottom_px[1] < 40 && bottom_px[2] > bottom_px[1], "{bottom_px:?}");
    // The right view shows the same box from behind, mirrored about its own centre.
    assert_ne!(image.get(320 + 160, 328), WHITE);
    assert_eq!(image.get(320 + 10, 328), WHITE);
}

#[test]
fn the_colour_bar_runs_from_the_lowest_colour_up_to_the_highest() {
    let mesh = cuboid(1.0, 2.0, 0.2);
    let heights: Vec<f64> = mesh.positions.iter().map(|p| p.y).collect();
    let image = render_heatmap(&mesh, Scalar::PerVertex(&heights), &RenderConfig::default()).unwrap();
    let bar_x = 2 * 320 + 20;
    let [r, g, b] = colormap(1.0);
    assert_eq!(image.get(bar_x, TITLE_HEIGHT + 30), [r, g, b, 255]);
    let [r, g, b] = colormap(0.0);
    assert_eq!(image.get(bar_x, TITLE_HEIGHT + 600 - 21), [r, g, b, 255]);

    let without = RenderConfig { colour_bar: false, ..RenderConfig::default() };
    let image = render_heatmap(&mesh, Scalar::PerVertex(&heights), &without).unwrap();
    assert_eq!(image.width, 640);
}

/// Two overlapping squares facing ±z at different depths, coloured by face: from +z
/// the nearer (z = +0.1, scalar 1) hides the other, from −z it is the other way round.
#[test]
fn the_z_buffer_keeps_the_nearest_surface_in_each_view() {
    let square = |z: f64, half: f64| {
        [Vec3::new(-half, 0.0, z), Vec3::new(half, 0.0, z), Vec3::new(half, 2.0, z), Vec3::new(-half, 2.0, z)]
    };
    let positions: Vec<Vec3> = square(0.1, 0.4).into_iter().chain(square(-0.1, 0.5)).collect();
    let faces = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
    let mesh = TriMesh { positions, faces };
    let values = [1.0, 1.0, 0.0, 0.0];
    let config =
        RenderConfig { up: Some(Direction::PosY), front: Some(Direction::PosZ), ..RenderConfig::default() };
    let image = render_heatmap(&mesh, Scalar::PerFace(&values), &config).unwrap();
    let is_yellow = |p: [u8; 4]| p[0] > 120 && p[1] > 120 && p[2] < 80;
    let centre_y = TITLE_HEIGHT + 300;
    assert!(is_yellow(image.get(160, centre_y)), "{:?}", image.get(160, centre_y));
    assert!(!is_yellow(image.get(320 + 160, centre_y)), "{:?}", image.get(480, centre_y));
}

#[test]
fn up_is_the_longest_extent_and_the_camera_looks_along_the_shortest() {
    // SCAPE is x up (height ~1.8 m, arm span ~1 m in the A pose, depth ~0.3 m).
    let scape_like = TriMesh {
        positions: vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.8, 1.0, 0.3)],
        faces: vec![[0, 1, 0]],
    };
    let frame = resolve_frame(&scape_like, &RenderConfig::default()).unwrap();
    assert_eq!((frame.up, frame.front), (Direction::PosX, Direction::PosZ));
    let sample_like = cuboid(0.8, 1.7, 0.3);
    let frame = resolve_frame(&sample_like, &RenderConfig::default()).unwrap();
    assert_eq!((frame.up, frame.front), (Direction::PosY, Direction::PosZ));
    let given = RenderConfig { up: Some(Direction::NegZ), ..RenderConfig::default() };
    let frame = resolve_frame(&sample_like, &given).unwrap();
    assert_eq!((frame.up, frame.front), (Direction::NegZ, Direction::PosX));
}

#[test]
fn bad_inputs_are_errors() {
    let mesh = cuboid(1.0, 1.0, 1.0);
    let short = [0.0; 5];
    assert_eq!(
        render_heatmap(&mesh, Scalar::PerVertex(&short), &RenderConfig::default()).unwrap_err(),
        VizError::ScalarLength { kind: "vertex", expected: 8, found: 5 }
    );
    let parallel =
        RenderConfig { up: Some(Direction::PosY), front: Some(Direction::NegY), ..RenderConfig::default() };
    assert!(matches!(
        render_heatmap(&mesh, Scalar::PerFace(&[0.0; 12]), &parallel),
        Err(VizError::ParallelAxes { .. })
    ));
    let empty = TriMesh::default();
    assert!(matches!(
        render_heatmap(&empty, Scalar::PerVertex(&[]), &RenderConfig::default()),
        Err(VizError::EmptyMesh { .. })
    ));
}

#[test]
fn the_png_decodes_to_the_rendered_image() {
    let mesh = cuboid(1.0, 2.0, 0.2);
    let config = RenderConfig {
        view_width: 64,
        view_height: 96,
        title: "height".into(),
        units: "m".into(),
        ..RenderConfig::default()
    };
    let values = [f64::NAN; 12];
    let image = render_heatmap(&mesh, Scalar::PerFace(&values), &config).unwrap();
    let bytes = encode_png(&image).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (2 * 64 + BAR_PANEL_WIDTH, TITLE_HEIGHT + 96));
    assert_eq!(&buf[..info.buffer_size()], &image.pixels[..]);
    // NaN faces are drawn in the missing colour (grey, shaded), not skipped.
    let centre = image.get(32, TITLE_HEIGHT + 48);
    assert!(centre[0] == centre[1] && centre[1] == centre[2] && centre[0] < 255, "{centre:?}");
}
