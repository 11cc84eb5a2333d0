//! Independent oracles: ply-rs-bw for PLY (both directions) and tobj for OBJ triangle geometry.

mod common;

use common::*;
use meshpyr::io::{MeshFormat, read_mesh, read_mesh_bytes, write_mesh_bytes};
use meshpyr::mesh::{Attribute, AttributeData, ElementProperty, PolygonMesh};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType as PScalar,
};
use ply_rs_bw::writer::Writer;

/// Reads PLY bytes with ply-rs-bw into a comparable form:
/// (element name, property names, rows of property values).
type Table = Vec<(String, Vec<String>, Vec<Vec<Property>>)>;

fn oracle_read(bytes: &[u8]) -> Table {
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .expect("ply-rs-bw rejects our output");
    ply.header
        .elements
        .values()
        .map(|e| {
            let names: Vec<String> = e.properties.keys().cloned().collect();
            let rows = ply.payload[&e.name]
                .iter()
                .map(|r| names.iter().map(|n| r[n].clone()).collect())
                .collect();
            (e.name.clone(), names, rows)
        })
        .collect()
}

/// The same table computed from our mesh.
fn our_table(m: &PolygonMesh) -> Table {
    let val = |d: &AttributeData, i: usize| match d {
        AttributeData::I8(v) => Property::Char(v[i]),
        AttributeData::U8(v) => Property::UChar(v[i]),
        AttributeData::I16(v) => Property::Short(v[i]),
        AttributeData::U16(v) => Property::UShort(v[i]),
        AttributeData::I32(v) => Property::Int(v[i]),
        AttributeData::U32(v) => Property::UInt(v[i]),
        AttributeData::F32(v) => Property::Float(v[i]),
        AttributeData::F64(v) => Property::Double(v[i]),
    };
    let double = m.position_type == Some(meshpyr::mesh::ScalarType::F64);
    let mut t = Table::new();
    let mut names: Vec<String> = ["x", "y", "z"].map(String::from).to_vec();
    names.extend(m.vertex_attributes.iter().map(|a| a.name.clone()));
    let rows = (0..m.n_vertices())
        .map(|i| {
            let p = m.positions[i];
            let mut r: Vec<Property> = p
                .to_array()
                .iter()
                .map(|&c| {
                    if double {
                        Property::Double(c)
                    } else {
                        Property::Float(c as f32)
                    }
                })
                .collect();
            r.extend(m.vertex_attributes.iter().map(|a| val(&a.data, i)));
            r
        })
        .collect();
    t.push(("vertex".into(), names, rows));
    let mut names = vec!["vertex_indices".to_string()];
    names.extend(m.face_attributes.iter().map(|a| a.name.clone()));
    let rows = (0..m.n_faces())
        .map(|f| {
            let mut r = vec![Property::ListInt(
                m.face(f).iter().map(|&v| v as i32).collect(),
            )];
            r.extend(m.face_attributes.iter().map(|a| val(&a.data, f)));
            r
        })
        .collect();
    t.push(("face".into(), names, rows));
    for e in &m.extra_elements {
        let names = e
            .properties
            .iter()
            .map(|p| match p {
                ElementProperty::Scalar(a) => a.name.clone(),
                ElementProperty::List(l) => l.name.clone(),
            })
            .collect();
        let rows = (0..e.rows)
            .map(|r| {
                e.properties
                    .iter()
                    .map(|p| match p {
                        ElementProperty::Scalar(a) => val(&a.data, r),
                        ElementProperty::List(l) => {
                            let it = &l.items[l.starts[r] as usize..l.starts[r + 1] as usize];
                            use meshpyr::mesh::ScalarType as S;
                            match l.item_type {
                                S::I8 => Property::ListChar(it.iter().map(|&x| x as i8).collect()),
                                S::U8 => Property::ListUChar(it.iter().map(|&x| x as u8).collect()),
                                S::I16 => {
                                    Property::ListShort(it.iter().map(|&x| x as i16).collect())
                                }
                                S::U16 => {
                                    Property::ListUShort(it.iter().map(|&x| x as u16).collect())
                                }
                                S::I32 => Property::ListInt(it.iter().map(|&x| x as i32).collect()),
                                S::U32 => {
                                    Property::ListUInt(it.iter().map(|&x| x as u32).collect())
                                }
                                S::F32 => {
                                    Property::ListFloat(it.iter().map(|&x| x as f32).collect())
                                }
                                S::F64 => Property::ListDouble(it.to_vec()),
                            }
                        }
                    })
                    .collect()
            })
            .collect();
        t.push((e.name.clone(), names, rows));
    }
    t
}

#[test]
fn ply_rs_bw_reads_our_files_identically() {
    let mut meshes = vec![rich_mesh()];
    for name in [
        "tetrahedron.ply",
        "cube_quad_poly.ply",
        "joint.ply",
        "planar_pymeshfix_vtk.ply",
    ] {
        meshes.push(read_mesh(data(name)).unwrap());
    }
    let mut dbl = rich_mesh();
    dbl.position_type = Some(meshpyr::mesh::ScalarType::F64);
    dbl.positions[0].x = 0.1;
    meshes.push(dbl);
    for m in &meshes {
        for enc in ENCODINGS {
            let bytes = write_mesh_bytes(m, MeshFormat::Ply, &ply(enc)).unwrap();
            assert_eq!(oracle_read(&bytes), our_table(m), "{enc:?}");
            // And comments.
            let header = Parser::<DefaultElement>::new()
                .read_ply(&mut &bytes[..])
                .unwrap()
                .header;
            let mut all = header.comments.clone();
            all.extend(header.obj_infos.iter().map(|o| format!("obj_info {o}")));
            assert_eq!(all.len(), m.comments.len());
        }
    }
}

/// A file written by ply-rs-bw (with types and layouts our writer never produces).
fn oracle_file(enc: Encoding) -> Vec<u8> {
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = enc;
    ply.header.comments.push("written by ply-rs-bw".into());
    let mut v = ElementDef::new("vertex".into());
    for (n, t) in [
        ("nx", PScalar::Float),
        ("x", PScalar::Double),
        ("y", PScalar::Double),
        ("z", PScalar::Double),
        ("confidence", PScalar::UShort),
    ] {
        v.properties
            .add(PropertyDef::new(n.into(), PropertyType::Scalar(t)));
    }
    ply.header.elements.add(v);
    let mut f = ElementDef::new("face".into());
    f.properties.add(PropertyDef::new(
        "label".into(),
        PropertyType::Scalar(PScalar::Char),
    ));
    f.properties.add(PropertyDef::new(
        "vertex_index".into(),
        PropertyType::List(PScalar::UShort, PScalar::UInt),
    ));
    ply.header.elements.add(f);
    let mut e = ElementDef::new("camera".into());
    e.properties.add(PropertyDef::new(
        "k".into(),
        PropertyType::List(PScalar::UChar, PScalar::Double),
    ));
    ply.header.elements.add(e);

    let verts = (0..5)
        .map(|i| {
            let mut el = DefaultElement::new();
            el.insert("nx".into(), Property::Float(i as f32 * 0.1));
            el.insert("x".into(), Property::Double(i as f64 / 3.0));
            el.insert("y".into(), Property::Double(-(i as f64) * 1e-3));
            el.insert("z".into(), Property::Double(1e10 + i as f64));
            el.insert("confidence".into(), Property::UShort(1000 * i));
            el
        })
        .collect();
    ply.payload.insert("vertex".into(), verts);
    let faces = [vec![0u32, 1, 2], vec![2, 3, 4, 0], vec![4, 3, 1]]
        .into_iter()
        .enumerate()
        .map(|(k, idx)| {
            let mut el = DefaultElement::new();
            el.insert("label".into(), Property::Char(-(k as i8)));
            el.insert("vertex_index".into(), Property::ListUInt(idx));
            el
        })
        .collect();
    ply.payload.insert("face".into(), faces);
    let mut cam = DefaultElement::new();
    cam.insert("k".into(), Property::ListDouble(vec![500.0, 0.25, 320.5]));
    ply.payload.insert("camera".into(), vec![cam]);
    let mut out = Vec::new();
    Writer::new().write_ply(&mut out, &mut ply).unwrap();
    out
}

#[test]
fn we_read_ply_rs_bw_files_identically() {
    for enc in [
        Encoding::Ascii,
        Encoding::BinaryLittleEndian,
        Encoding::BinaryBigEndian,
    ] {
        let bytes = oracle_file(enc);
        let m = read_mesh_bytes(&bytes, MeshFormat::Ply).unwrap();
        assert_eq!(m.position_type, Some(meshpyr::mesh::ScalarType::F64));
        assert_eq!(m.n_vertices(), 5);
        for i in 0..5 {
            assert_eq!(m.positions[i].x.to_bits(), (i as f64 / 3.0).to_bits());
            assert_eq!(m.positions[i].z, 1e10 + i as f64);
        }
        assert_eq!(
            m.faces().collect::<Vec<_>>(),
            vec![&[0, 1, 2][..], &[2, 3, 4, 0], &[4, 3, 1]]
        );
        assert_eq!(
            m.vertex_attributes[0],
            Attribute {
                name: "nx".into(),
                data: AttributeData::F32((0..5).map(|i| i as f32 * 0.1).collect())
            }
        );
        assert_eq!(
            m.vertex_attributes[1].data,
            AttributeData::U16(vec![0, 1000, 2000, 3000, 4000])
        );
        assert_eq!(
            m.face_attributes[0].data,
            AttributeData::I8(vec![0, -1, -2])
        );
        assert_eq!(m.extra_elements.len(), 1);
        let ElementProperty::List(l) = &m.extra_elements[0].properties[0] else {
            panic!()
        };
        assert_eq!(l.items, vec![500.0, 0.25, 320.5]);
        assert_eq!(m.comments, vec!["written by ply-rs-bw".to_string()]);
        // And what we write back reads identically in ply-rs-bw.
        for ours in ENCODINGS {
            let b = write_mesh_bytes(&m, MeshFormat::Ply, &ply(ours)).unwrap();
            assert_eq!(oracle_read(&b), our_table(&m));
        }
    }
    // Real files (written by other tools) agree with ply-rs-bw.
    for name in [
        "cone20.ply",
        "planar_pymeshfix_vtk.ply",
        "dodecahedron_poly.ply",
    ] {
        let bytes = data_bytes(name);
        let m = read_mesh_bytes(&bytes, MeshFormat::Ply).unwrap();
        assert_eq!(oracle_read(&bytes), our_table(&m), "{name}");
    }
}

#[test]
fn tobj_agrees_on_triangle_geometry() {
    // tobj re-indexes vertices, so compare the triangles' corner coordinates.
    let load = |bytes: &[u8]| {
        let opts = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj_buf(&mut &bytes[..], &opts, |_| {
            Err(tobj::LoadError::GenericFailure)
        })
        .unwrap();
        let mut tris = Vec::new();
        for m in models {
            let p = &m.mesh.positions;
            for t in m.mesh.indices.chunks_exact(3) {
                tris.push([t[0], t[1], t[2]].map(|i| {
                    let i = i as usize * 3;
                    [p[i], p[i + 1], p[i + 2]].map(f64::from)
                }));
            }
        }
        tris
    };
    let ours = |m: &PolygonMesh| {
        let mut tris = Vec::new();
        for f in m.faces() {
            for k in 2..f.len() {
                tris.push([f[0], f[k - 1], f[k]].map(|v| m.positions[v as usize].to_array()));
            }
        }
        tris
    };
    // A file with groups, relative indices, quads and an unreferenced vertex.
    let src = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\ng a\nf 1 2 3 4\ng b\nf -1 -2 -4\n";
    let m = read_mesh_bytes(src, MeshFormat::Obj).unwrap();
    assert_eq!(m.n_vertices(), 5);
    assert_eq!(ours(&m), load(src));
    // A mesh written by us and the real OBJ test file.
    let dodo = read_mesh(data("dodecahedron_poly.ply")).unwrap();
    let b = write_mesh_bytes(&dodo, MeshFormat::Obj, &Default::default()).unwrap();
    let r = read_mesh_bytes(&b, MeshFormat::Obj).unwrap();
    assert_eq!(ours(&r), load(&b));
    let cube = data_bytes("cube_degenerate_om.obj");
    let mut theirs = load(&cube);
    let mut mine = ours(&read_mesh_bytes(&cube, MeshFormat::Obj).unwrap());
    // tobj drops polygons with repeated corners differently; compare as sorted multisets.
    let key = |t: &[[f64; 3]; 3]| t.map(|p| p.map(f64::to_bits));
    theirs.sort_by_key(key);
    mine.sort_by_key(key);
    assert_eq!(mine, theirs);
}
