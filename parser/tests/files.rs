//! Scene files on disk: `Include`, `Import`, gzip-compressed files, relative paths, and the
//! errors for files that cannot be read.

use nimbus_parser::{Directive, MaterialRef, load_file, load_str};

use crate::common::{TempDir, assert_mat_close, rows};

/// The radius of a sphere shape.
fn radius(shape: &nimbus_parser::ShapeEntity) -> f32 {
    shape.entity.params.get_one_float("radius", 1.0).unwrap()
}

fn path_str(p: &std::path::Path) -> String {
    p.to_string_lossy().into_owned()
}

#[test]
fn include_splices_the_file_in_place() {
    let dir = TempDir::new();
    dir.write("materials.pbrt", "MakeNamedMaterial \"gold\" \"string type\" \"conductor\"\nTranslate 0 0 5\n");
    let main =
        dir.write("scene.pbrt", "WorldBegin\nInclude \"materials.pbrt\"\nNamedMaterial \"gold\"\nShape \"sphere\"\n");
    let scene = load_file(&main).unwrap();
    assert_eq!(scene.named_materials[0].name, "gold");
    assert_eq!(scene.shapes[0].material, MaterialRef::Named("gold".into()));
    // Unlike Import, an included file's graphics state carries on in the includer.
    assert_mat_close(
        scene.shapes[0].world_from_object.start,
        rows([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 5.0], [0.0, 0.0, 0.0, 1.0]]),
    );
    // Locations name the file each directive came from.
    let included = dir.path().join("materials.pbrt");
    assert_eq!(scene.named_materials[0].entity.loc.to_string(), format!("{}:1:1", included.display()));
    assert_eq!(scene.shapes[0].entity.loc.to_string(), format!("{}:4:1", main.display()));
    assert_eq!(scene.files, [path_str(&main), path_str(&included)]);
}

#[test]
fn a_parameter_list_continues_after_the_included_file_ends() {
    let dir = TempDir::new();
    dir.write("shape.pbrt", "Shape \"sphere\" \"float radius\" 2");
    let main = dir.write("scene.pbrt", "WorldBegin\nInclude \"shape.pbrt\"\n  \"float zmax\" 0.5\nShape \"sphere\"");
    let scene = load_file(&main).unwrap();
    assert_eq!(scene.shapes.len(), 2);
    let p = &scene.shapes[0].entity.params;
    assert_eq!(p.get_one_float("radius", 1.0), Ok(2.0));
    assert_eq!(p.get_one_float("zmax", 1.0), Ok(0.5));
    assert_eq!(p.loc("zmax").unwrap().to_string(), format!("{}:3:3", main.display()));
    assert!(scene.shapes[1].entity.params.is_empty());
}

/// pbrt-v4 resolves every relative path from the directory of the scene file named on the
/// command line (its search directory), not from the file that names it: scenes such as San
/// Miguel include `geometry/x.pbrt`, which names `geometry/y.ply` relative to the top.
#[test]
fn include_paths_resolve_from_the_scene_directory() {
    let dir = TempDir::new();
    // scene.pbrt includes sub/a.pbrt, which includes b.pbrt: that is the b.pbrt beside
    // scene.pbrt, not sub/b.pbrt (which would fail to parse); and sub/c.pbrt by its path
    // from the top.
    dir.write("b.pbrt", "Shape \"sphere\" \"float radius\" 2\n");
    dir.write("sub/b.pbrt", "this is not a scene");
    dir.write("sub/c.pbrt", "Shape \"sphere\" \"float radius\" 4\n");
    dir.write("sub/a.pbrt", "Include \"b.pbrt\"\nInclude \"sub/c.pbrt\"\nShape \"sphere\" \"float radius\" 1\n");
    let main = dir.write("scene.pbrt", "WorldBegin\nInclude \"sub/a.pbrt\"\nShape \"sphere\" \"float radius\" 3\n");
    let scene = load_file(&main).unwrap();
    let radii: Vec<f32> = scene.shapes.iter().map(radius).collect();
    assert_eq!(radii, [2.0, 4.0, 1.0, 3.0]);
    let b = dir.path().join("b.pbrt");
    assert_eq!(scene.shapes[0].entity.loc.to_string(), format!("{}:1:1", b.display()));
    // Every location carries the scene's directory, however deep the include.
    assert_eq!(scene.shapes[1].entity.loc.directory(), dir.path());
    // A path relative only to the included file's directory is not found, and the error
    // names where it was written and the path tried.
    dir.write("sub/d.pbrt", "Include \"e.pbrt\"\n");
    dir.write("sub/e.pbrt", "Shape \"sphere\"\n");
    let main = dir.write("scene2.pbrt", "WorldBegin\nInclude \"sub/d.pbrt\"\n");
    let e = load_file(&main).unwrap_err().to_string();
    let tried = std::path::absolute(dir.path().join("e.pbrt")).unwrap();
    assert!(e.starts_with(&format!("{}:1:1: Include \"e.pbrt\"", dir.path().join("sub/d.pbrt").display())), "{e}");
    assert!(e.contains(&format!("(tried {})", tried.display())), "{e}");
}

/// Imported files resolve their paths from the scene's directory too.
#[test]
fn import_paths_resolve_from_the_scene_directory() {
    let dir = TempDir::new();
    dir.write("parts/lib.pbrt", "Include \"parts/shape.pbrt\"\n");
    dir.write("parts/shape.pbrt", "Shape \"sphere\" \"float radius\" 6\n");
    let main = dir.write("scene.pbrt", "WorldBegin\nImport \"parts/lib.pbrt\"\n");
    assert_eq!(radius(&load_file(&main).unwrap().shapes[0]), 6.0);
}

#[test]
fn absolute_include_paths_are_used_as_they_are() {
    let dir = TempDir::new();
    let inc = dir.write("elsewhere/inc.pbrt", "Shape \"sphere\" \"float radius\" 4\n");
    let main = dir.write("deep/er/scene.pbrt", &format!("WorldBegin\nInclude \"{}\"\n", inc.display()));
    let scene = load_file(&main).unwrap();
    assert_eq!(radius(&scene.shapes[0]), 4.0);
}

#[test]
fn scene_text_resolves_includes_against_its_name() {
    let dir = TempDir::new();
    dir.write("inc.pbrt", "Shape \"sphere\" \"float radius\" 5\n");
    let name = dir.path().join("virtual.pbrt");
    let scene = load_str("WorldBegin\nInclude \"inc.pbrt\"", &path_str(&name)).unwrap();
    assert_eq!(radius(&scene.shapes[0]), 5.0);
}

#[test]
fn errors_in_an_included_file_name_that_file() {
    let dir = TempDir::new();
    dir.write("bad.pbrt", "# first line\n  Shape \"sphere\" \"float radius\" [ 1 x ]\n");
    let main = dir.write("scene.pbrt", "WorldBegin\nInclude \"bad.pbrt\"\n");
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!("{}:2:37: \"x\": expected a number for \"float radius\"", dir.path().join("bad.pbrt").display())
    );
    dir.write("unterminated.pbrt", "Shape \"sphere\n");
    let main = dir.write("scene2.pbrt", "WorldBegin\n\nInclude \"unterminated.pbrt\"\n");
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!(
            "{}:1:7: unterminated string: newline before the closing '\"'",
            dir.path().join("unterminated.pbrt").display()
        )
    );
}

#[test]
fn missing_include_file() {
    let dir = TempDir::new();
    let main = dir.write("scene.pbrt", "WorldBegin\n\n  Include \"missing.pbrt\"\n");
    let e = load_file(&main).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "{}:3:3: Include \"missing.pbrt\": cannot read it (tried {}): No such file or directory (os error 2)",
            main.display(),
            std::path::absolute(dir.path().join("missing.pbrt")).unwrap().display()
        )
    );
    // From a string, relative paths resolve against the current directory.
    assert_eq!(
        load_str("Include \"no/such/file.pbrt\"", "t.pbrt").unwrap_err().to_string(),
        format!(
            "t.pbrt:1:1: Include \"no/such/file.pbrt\": cannot read it (tried {}): No such file or directory (os error 2)",
            std::path::absolute("no/such/file.pbrt").unwrap().display()
        )
    );
}

#[test]
fn missing_import_file() {
    let dir = TempDir::new();
    let main = dir.write("scene.pbrt", "WorldBegin\nImport \"gone.pbrt\"\n");
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!(
            "{}:2:1: Import \"gone.pbrt\": cannot read it (tried {}): No such file or directory (os error 2)",
            main.display(),
            std::path::absolute(dir.path().join("gone.pbrt")).unwrap().display()
        )
    );
}

#[test]
fn missing_main_file() {
    let dir = TempDir::new();
    let path = dir.path().join("nothing.pbrt");
    let e = load_file(&path).unwrap_err();
    assert_eq!(e.loc, None);
    assert_eq!(
        e.message,
        format!("{}: cannot read scene file: No such file or directory (os error 2)", path.display())
    );
}

#[test]
fn a_file_that_includes_itself_is_stopped() {
    let dir = TempDir::new();
    let looping = dir.write("loop.pbrt", "# includes itself\nInclude \"loop.pbrt\"\n");
    let main = dir.write("scene.pbrt", "WorldBegin\nInclude \"loop.pbrt\"\n");
    let e = load_file(&main).unwrap_err();
    assert_eq!(e.loc, None);
    assert_eq!(
        e.message,
        format!("{}: Include nested more than 64 deep (does a file include itself?)", looping.display())
    );
}

#[test]
fn a_file_that_imports_itself_is_stopped() {
    let dir = TempDir::new();
    let main = dir.write("loop.pbrt", "WorldBegin\nImport \"loop.pbrt\"\n");
    // The first Import reads the file again, whose WorldBegin is an error in the world block.
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!("{}:1:1: WorldBegin is not allowed after WorldBegin (options block only)", main.display())
    );
    let world = dir.write("world.pbrt", "WorldBegin\nImport \"a.pbrt\"\n");
    dir.write("a.pbrt", "Import \"a.pbrt\"\n");
    assert_eq!(
        load_file(&world).unwrap_err().to_string(),
        format!("{}:1:1: Import nested too deeply (does a file import itself?)", dir.path().join("a.pbrt").display())
    );
}

#[test]
fn gzip_compressed_scenes_includes_and_imports() {
    let dir = TempDir::new();
    dir.write_gz("inc.pbrt.gz", "Shape \"sphere\" \"float radius\" 2\n");
    dir.write_gz("imp.pbrt.gz", "Shape \"sphere\" \"float radius\" 3\n");
    let main = dir.write_gz(
        "scene.pbrt.gz",
        "Camera \"orthographic\"\nWorldBegin\nInclude \"inc.pbrt.gz\"\nImport \"imp.pbrt.gz\"\n  Shape \"sphere\" \"float radius\" [ x ]",
    );
    // Errors point into the compressed file by its line and column.
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!("{}:5:35: \"x\": expected a number for \"float radius\"", main.display())
    );
    let main = dir.write_gz(
        "scene.pbrt.gz",
        "Camera \"orthographic\"\nWorldBegin\nInclude \"inc.pbrt.gz\"\nImport \"imp.pbrt.gz\"\n",
    );
    let scene = load_file(&main).unwrap();
    assert_eq!(scene.camera.entity.name, "orthographic");
    let radii: Vec<f32> = scene.shapes.iter().map(radius).collect();
    assert_eq!(radii, [2.0, 3.0]);
    assert_eq!(
        scene.files,
        [path_str(&main), path_str(&dir.path().join("inc.pbrt.gz")), path_str(&dir.path().join("imp.pbrt.gz")),]
    );
}

#[test]
fn a_corrupt_gzip_file_is_an_error() {
    let dir = TempDir::new();
    let bad = dir.write("bad.pbrt.gz", "WorldBegin\n");
    let e = load_file(&bad).unwrap_err();
    assert_eq!(e.loc, None);
    assert_eq!(e.message, format!("{}: cannot read scene file: invalid gzip header", bad.display()));
}

#[test]
fn import_is_only_allowed_in_the_world_block() {
    let dir = TempDir::new();
    dir.write("geometry.pbrt", "Shape \"sphere\"\n");
    let main = dir.write("scene.pbrt", "Camera \"perspective\"\n  Import \"geometry.pbrt\"\nWorldBegin\n");
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!("{}:2:3: Import is not allowed before WorldBegin (world block only)", main.display())
    );
}

#[test]
fn imported_graphics_state_does_not_leak() {
    let dir = TempDir::new();
    dir.write(
        "part.pbrt",
        "Translate 0 0 7\nReverseOrientation\nMaterial \"conductor\"\n\
         MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
         MediumInterface \"fog\" \"\"\nAreaLightSource \"diffuse\"\nColorSpace \"rec2020\"\n\
         Attribute \"shape\" \"float radius\" 9\nCoordinateSystem \"inner\"\n\
         Texture \"t\" \"float\" \"constant\"\n\
         MakeNamedMaterial \"m\" \"string type\" \"diffuse\"\n\
         Shape \"sphere\"\n",
    );
    let main = dir.write(
        "scene.pbrt",
        "WorldBegin\nTranslate 1 0 0\nImport \"part.pbrt\"\n\
         Shape \"sphere\"\nCoordSysTransform \"inner\"\n\
         MediumInterface \"fog\" \"fog\"\nNamedMaterial \"m\"\n\
         Shape \"sphere\" \"texture alpha\" \"t\"\n",
    );
    let scene = load_file(&main).unwrap();
    let [inside, after, last] = &scene.shapes[..] else {
        panic!("{:?}", scene.shapes);
    };
    let translate =
        |x: f64, z: f64| rows([[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]]);
    // Inside the imported file, the importer's state applies and the file's own changes too.
    assert_mat_close(inside.world_from_object.start, translate(1.0, 7.0));
    assert!(inside.reverse_orientation);
    assert_eq!(inside.material, MaterialRef::Index(1));
    assert_eq!(inside.area_light, Some(0));
    assert_eq!(inside.entity.color_space, nimbus_parser::ColorSpace::Rec2020);
    assert_eq!(radius(inside), 9.0);
    assert_eq!(
        inside.medium_interface,
        Some(nimbus_parser::MediumInterface { inside: Some("fog".into()), outside: None })
    );
    // After the Import, none of it is left.
    assert_mat_close(after.world_from_object.start, translate(1.0, 0.0));
    assert!(!after.reverse_orientation);
    assert_eq!(after.material, MaterialRef::Index(0));
    assert_eq!(after.area_light, None);
    assert_eq!(after.entity.color_space, nimbus_parser::ColorSpace::Srgb);
    assert_eq!(radius(after), 1.0);
    assert_eq!(after.medium_interface, None);
    assert_eq!(after.outside_medium, None);
    // The coordinate system named inside the import is gone too: CoordSysTransform warns
    // and leaves the transform alone.
    assert_mat_close(last.world_from_object.start, translate(1.0, 0.0));
    assert_eq!(
        scene.warnings.iter().map(|w| w.to_string()).collect::<Vec<_>>(),
        [format!("{}:5:1: couldn't find named coordinate system \"inner\"", main.display())]
    );
    // But what it defined by name stays defined: the medium, the material and the texture.
    assert_eq!(last.material, MaterialRef::Named("m".into()));
    assert_eq!(last.outside_medium, Some("fog".into()));
    assert_eq!(scene.textures[0].name, "t");
}

#[test]
fn import_must_balance_its_attribute_blocks() {
    let dir = TempDir::new();
    dir.write("open.pbrt", "\nAttributeBegin\nShape \"sphere\"\n");
    dir.write("close.pbrt", "Shape \"sphere\"\nAttributeEnd\n");
    let main = dir.write("a.pbrt", "WorldBegin\nImport \"open.pbrt\"\n");
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!(
            "{}:2:1: AttributeBegin has no matching AttributeEnd in the file imported at {}:2:1",
            dir.path().join("open.pbrt").display(),
            main.display()
        )
    );
    // An imported file cannot close the importer's block.
    let main = dir.write("b.pbrt", "WorldBegin\nAttributeBegin\nImport \"close.pbrt\"\nAttributeEnd\n");
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!("{}:2:1: AttributeEnd without matching AttributeBegin", dir.path().join("close.pbrt").display())
    );
}

#[test]
fn an_imported_file_is_parsed_on_its_own() {
    // Unlike Include, Import does not splice tokens: a parameter list cannot run on past the
    // end of an imported file.
    let dir = TempDir::new();
    dir.write("shape.pbrt", "Shape \"sphere\"");
    let main = dir.write("scene.pbrt", "WorldBegin\nImport \"shape.pbrt\" \"float radius\" 2\n");
    assert_eq!(
        load_file(&main).unwrap_err().to_string(),
        format!("{}:2:21: expected a directive, found string \"float radius\"", main.display())
    );
}

#[test]
fn the_directive_recorder_does_not_follow_files() {
    // directives_of_str keeps Include and Import as directives and reads no file.
    assert_eq!(
        crate::common::directives("Include \"no/such.pbrt\"\nImport \"nor/this.pbrt\""),
        [Directive::Include("no/such.pbrt".into()), Directive::Import("nor/this.pbrt".into()),]
    );
}
