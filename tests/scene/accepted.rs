//! Scenes the loader must accept, and the values it must give them
//! (docs/scene-format.md: Elements, Transformations, Numbers and Everything
//! else in the file).

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use rayoflight::math::{TransformStep, Vec3};
use rayoflight::scene::{self, Illumination, Material, Model, Scene, Shape};

const CAMERA: &str = r#"<camera width="4" height="3" eyeDistance="1"/>"#;

fn parse(text: &str) -> Scene {
    scene::parse(text, Path::new("test.xml")).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// A scene with the camera and `body` inside `<scene>`.
fn with_camera(body: &str) -> Scene {
    parse(&format!("<scene>{CAMERA}{body}</scene>"))
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-12
}

fn origin_of(object: &scene::Object) -> Vec3 {
    object.transform.to_world().transform_point3(Vec3::ZERO)
}

#[test]
fn the_example_loads_with_its_values() {
    let s = parse(rayoflight::EXAMPLE_SCENE);
    assert_eq!(s.objects.len(), 2);

    let green = &s.objects[0];
    assert_eq!(green.shape, Shape::Sphere);
    assert_eq!(green.color, Vec3::new(0.2, 0.8, 0.2));
    assert_eq!(
        green.material,
        Material {
            ka: 0.3,
            kd: 0.3,
            ks: 0.3,
            m: 20.0
        }
    );
    assert_eq!(
        green.transform.steps(),
        &[TransformStep::Translate(Vec3::new(2.0, 0.0, -2.0))]
    );
    assert!(close(origin_of(green), Vec3::new(2.0, 0.0, -2.0)));

    let red = &s.objects[1];
    assert_eq!(red.shape, Shape::Sphere);
    assert_eq!(red.color, Vec3::new(1.0, 0.2, 0.0));
    assert_eq!(
        red.material,
        Material {
            ka: 0.4,
            kd: 0.5,
            ks: 0.3,
            m: 1.0
        }
    );
    assert!(close(origin_of(red), Vec3::new(-2.0, 0.0, -2.0)));

    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.lights[0].position, Vec3::new(1.0, -4.0, -2.0));
    assert_eq!(s.lights[0].color, Vec3::ONE);

    assert_eq!((s.camera.width, s.camera.height), (600, 600));
    assert_eq!(s.camera.eye_distance, 4.0);
    let eye = s
        .camera
        .transform
        .to_world()
        .transform_point3(Vec3::new(0.0, 0.0, -4.0));
    assert!(close(eye, Vec3::new(0.0, 0.0, -24.0)));

    assert_eq!(
        s.model,
        Model {
            illumination: Illumination::Whitted,
            depth: 2
        }
    );
}

#[test]
fn the_example_file_loads_from_disk() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/example.xml");
    let from_disk = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(from_disk, parse(rayoflight::EXAMPLE_SCENE));
}

#[test]
fn defaults_fill_what_the_file_leaves_out() {
    let s = with_camera(
        r#"<sphere/><plane></plane><light x="1" y="2" z="3"/>
           <sphere><material ks="0.7"/></sphere>"#,
    );
    assert_eq!(s.objects.len(), 3);
    for object in &s.objects {
        assert_eq!(object.color, Vec3::ONE);
        assert!(object.transform.is_identity());
        assert!(object.transform.steps().is_empty());
    }
    assert_eq!(s.objects[0].shape, Shape::Sphere);
    assert_eq!(s.objects[1].shape, Shape::Plane);
    assert_eq!(s.objects[0].material, Material::default());
    assert_eq!(
        Material::default(),
        Material {
            ka: 0.2,
            kd: 0.6,
            ks: 0.2,
            m: 10.0
        }
    );
    // Each material attribute defaults on its own.
    assert_eq!(
        s.objects[2].material,
        Material {
            ks: 0.7,
            ..Material::default()
        }
    );
    assert_eq!(s.lights[0].color, Vec3::ONE);
    assert!(s.camera.transform.is_identity());
    // No <model>: phong; depth 1.
    assert_eq!(
        s.model,
        Model {
            illumination: Illumination::Phong,
            depth: 1
        }
    );
    // whitted without depth: 1.
    let s = with_camera(r#"<model type="whitted"/>"#);
    assert_eq!(s.model.illumination, Illumination::Whitted);
    assert_eq!(s.model.depth, 1);
}

#[test]
fn depth_is_allowed_on_every_model_and_spans_its_range() {
    for model in Illumination::ALL {
        for depth in [0u32, 1, 7, 10_000] {
            let s = with_camera(&format!(
                r#"<model type="{}" depth="{depth}"/>"#,
                model.name()
            ));
            assert_eq!(
                s.model,
                Model {
                    illumination: model,
                    depth
                }
            );
        }
    }
}

#[test]
fn top_level_elements_and_object_children_come_in_any_order() {
    let s = parse(
        r#"<scene>
             <model type="lambert"/>
             <light x="0" y="-1" z="0"><color red="2" green="2" blue="2"/></light>
             <plane>
               <transformation><rotate-x angle="1.5"/></transformation>
               <material ka="0" kd="1" ks="0" m="1"/>
               <color red="0.5" green="0.25" blue="0"/>
             </plane>
             <camera width="8" height="6" eyeDistance="3"/>
           </scene>"#,
    );
    assert_eq!(s.model.illumination, Illumination::Lambert);
    // Colours above 1 are allowed.
    assert_eq!(s.lights[0].color, Vec3::splat(2.0));
    let plane = &s.objects[0];
    assert_eq!(plane.shape, Shape::Plane);
    assert_eq!(plane.color, Vec3::new(0.5, 0.25, 0.0));
    assert_eq!(plane.material.kd, 1.0);
    assert_eq!(plane.transform.steps(), &[TransformStep::RotateX(1.5)]);
    assert_eq!((s.camera.width, s.camera.height), (8, 6));
    assert_eq!(s.camera.eye_distance, 3.0);
}

#[test]
fn comments_declaration_and_processing_instructions_are_allowed_anywhere() {
    let s = parse(
        "\u{feff}<?xml version=\"1.0\" encoding=\"UTF-8\"?>\r\n\
         <!-- before the root -->\r\n\
         <?editor hint?>\r\n\
         <scene><!-- first -->\r\n\
         \t<sphere><!-- in an object -->\r\n\
         \t\t<color red=\"1\" green=\"0\" blue=\"0\"><!-- in a leaf --></color>\r\n\
         \t\t<transformation><!-- in a transformation --><?pi?>\r\n\
         \t\t\t<translate x=\"1\"><!-- in a step --></translate>\r\n\
         \t\t</transformation>\r\n\
         \t</sphere>\r\n\
         \t<camera width=\"4\" height=\"3\" eyeDistance=\"1\"><!-- c --></camera>\r\n\
         <!-- last --></scene>\r\n\
         <!-- after the root -->\r\n",
    );
    assert_eq!(s.objects.len(), 1);
    assert_eq!(s.objects[0].color, Vec3::X);
    assert!(close(origin_of(&s.objects[0]), Vec3::X));
}

#[test]
fn numbers_follow_rust_f64_syntax_with_references_and_padding() {
    let s = with_camera(
        r#"<light x="&#49;" y="&#x32;e1" z=" .5 "/>
           <light x="+2" y="1e3" z="-0"/>
           <light x='1E-2' y="	7	" z="0.000"/>"#,
    );
    assert_eq!(s.lights[0].position, Vec3::new(1.0, 20.0, 0.5));
    assert_eq!(s.lights[1].position, Vec3::new(2.0, 1000.0, 0.0));
    assert_eq!(s.lights[2].position, Vec3::new(0.01, 7.0, 0.0));
}

#[test]
fn integers_accept_a_leading_plus() {
    let s = parse(r#"<scene><camera width="+640" height="0480" eyeDistance="2.5"/></scene>"#);
    assert_eq!((s.camera.width, s.camera.height), (640, 480));
    assert_eq!(s.camera.eye_distance, 2.5);
}

#[test]
fn smallest_and_largest_images_are_accepted() {
    for (w, h) in [
        (1u32, 1u32),
        (1, 1000),
        (1000, 1),
        (16_384, 16_384),
        (1 << 28, 1),
    ] {
        assert!(u64::from(w) * u64::from(h) <= scene::MAX_PIXELS, "{w}x{h}");
        let s = parse(&format!(
            r#"<scene><camera width="{w}" height="{h}" eyeDistance="1"/></scene>"#
        ));
        assert_eq!((s.camera.width, s.camera.height), (w, h));
    }
}

#[test]
fn scale_forms() {
    let s = with_camera(
        r#"<sphere><transformation><scale factor="2"/></transformation></sphere>
           <sphere><transformation><scale x="3"/></transformation></sphere>
           <sphere><transformation><scale y="2" z="-1"/></transformation></sphere>
           <sphere><transformation><scale factor="-1"/></transformation></sphere>
           <sphere><transformation><scale/></transformation></sphere>"#,
    );
    let steps: Vec<&[TransformStep]> = s.objects.iter().map(|o| o.transform.steps()).collect();
    assert_eq!(steps[0], &[TransformStep::UniformScale(2.0)]);
    assert_eq!(steps[1], &[TransformStep::Scale(Vec3::new(3.0, 1.0, 1.0))]);
    assert_eq!(steps[2], &[TransformStep::Scale(Vec3::new(1.0, 2.0, -1.0))]);
    // A negative factor is a mirror image, not an error.
    assert_eq!(steps[3], &[TransformStep::UniformScale(-1.0)]);
    assert_eq!(steps[4], &[TransformStep::Scale(Vec3::ONE)]);
    let p = s.objects[0]
        .transform
        .to_world()
        .transform_point3(Vec3::new(1.0, 1.0, 1.0));
    assert!(close(p, Vec3::splat(2.0)));
}

#[test]
fn transformation_steps_apply_in_document_order() {
    let s = with_camera(
        r#"<sphere><transformation>
             <translate x="1"/>
             <rotate-z angle="1.5707963267948966"/>
             <rotate-y angle="0"/>
             <translate z="5"/>
           </transformation></sphere>
           <sphere><transformation>
             <rotate-z angle="1.5707963267948966"/>
             <translate x="1"/>
           </transformation></sphere>"#,
    );
    assert_eq!(
        s.objects[0].transform.steps(),
        &[
            TransformStep::Translate(Vec3::X),
            TransformStep::RotateZ(FRAC_PI_2),
            TransformStep::RotateY(0.0),
            TransformStep::Translate(Vec3::new(0.0, 0.0, 5.0)),
        ]
    );
    // Translate first, then rotate (x, y) -> (-y, x): the centre lands on +y.
    assert!(close(origin_of(&s.objects[0]), Vec3::new(0.0, 1.0, 5.0)));
    // Rotate first: the centre stays at the origin, then moves to +x.
    assert!(close(origin_of(&s.objects[1]), Vec3::X));
}

#[test]
fn many_lights_and_objects_are_accepted() {
    // docs/limits.md promises at least 10 000 lights and 1 000 000 objects.
    let mut text = format!("<scene>{CAMERA}\n");
    for i in 0..10_000 {
        text.push_str(&format!("<light x=\"{i}\" y=\"0\" z=\"0\"/>\n"));
    }
    for _ in 0..1_000_000 {
        text.push_str("<sphere/>\n");
    }
    text.push_str("</scene>\n");
    let s = parse(&text);
    assert_eq!(s.lights.len(), 10_000);
    assert_eq!(s.lights[9_999].position.x, 9_999.0);
    assert_eq!(s.objects.len(), 1_000_000);
    const { assert!(scene::MAX_LIGHTS >= 10_000 && scene::MAX_OBJECTS >= 1_000_000) };
    const { assert!(scene::MAX_FILE_BYTES >= 256 << 20 && scene::MAX_PIXELS >= 1 << 28) };
}
