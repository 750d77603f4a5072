//! VTK XML unstructured-grid (`.vtu`) and collection (`.pvd`) writers.
//!
//! Library choice: a small writer on `quick-xml` rather than `vtkio`.
//! `vtkio` 0.7 exists only as a release candidate, pulls a larger
//! dependency tree and needs our arrays copied into its own model; the VTU
//! subset we need (points, cells, point/cell data as ASCII `DataArray`s) is
//! ~100 lines, with escaping and well-formedness handled by `quick-xml`.
//!
//! Cell types: tet4 = 10, tet10 = 24 (Gmsh nodes 8 and 9 swapped into VTK
//! order), hex8 = 12. Symmetric tensors are written with 6 components in
//! ParaView's order `XX, YY, ZZ, XY, YZ, XZ`. Numbers use Rust's shortest
//! round-trip formatting, so values are exact.

use std::fmt::Write as _;

use quick_xml::Writer;
use quick_xml::events::BytesText;

use crate::mesh::ElementKind;

/// VTK cell type and node order of a volume kind.
#[must_use]
pub fn vtk_cell(kind: ElementKind, nodes: &[usize]) -> (u8, Vec<usize>) {
    match kind {
        ElementKind::Tet4 => (10, nodes.to_vec()),
        ElementKind::Hex8 => (12, nodes.to_vec()),
        ElementKind::Tet10 => {
            let mut v = nodes.to_vec();
            v.swap(8, 9);
            (24, v)
        }
        ElementKind::Tri3 => (5, nodes.to_vec()),
        ElementKind::Tri6 => (22, nodes.to_vec()),
        ElementKind::Quad4 => (9, nodes.to_vec()),
    }
}

/// A named data array with `components` values per point/cell.
#[derive(Clone, Debug)]
pub struct Field<'a> {
    /// Array name.
    pub name: &'a str,
    /// Components per tuple.
    pub components: usize,
    /// Values, tuple-major.
    pub values: &'a [f64],
}

/// Everything one `.vtu` contains.
#[derive(Clone, Debug)]
pub struct Grid<'a> {
    /// Point coordinates.
    pub points: &'a [[f64; 3]],
    /// Cells: VTK type and connectivity.
    pub cells: &'a [(u8, Vec<usize>)],
    /// Point data.
    pub point_data: Vec<Field<'a>>,
    /// Cell data.
    pub cell_data: Vec<Field<'a>>,
}

fn join<T: std::fmt::Display>(it: impl Iterator<Item = T>) -> String {
    let mut s = String::new();
    for (i, v) in it.enumerate() {
        if i > 0 {
            s.push(' ');
        }
        let _ = write!(s, "{v}");
    }
    s
}

fn data_array<W: std::io::Write>(
    w: &mut Writer<W>,
    ty: &str,
    name: &str,
    components: usize,
    text: &str,
) -> std::io::Result<()> {
    let comps = components.to_string();
    let mut el = w.create_element("DataArray").with_attribute(("type", ty));
    if !name.is_empty() {
        el = el.with_attribute(("Name", name));
    }
    el.with_attribute(("NumberOfComponents", comps.as_str()))
        .with_attribute(("format", "ascii"))
        .write_text_content(BytesText::from_escaped(text))?;
    Ok(())
}

/// Writes `<tag>` holding one `Float64` data array per field.
fn fields<W: std::io::Write>(
    w: &mut Writer<W>,
    tag: &str,
    list: &[Field<'_>],
) -> std::io::Result<()> {
    w.create_element(tag).write_inner_content(|w| {
        for f in list {
            data_array(w, "Float64", f.name, f.components, &join(f.values.iter()))?;
        }
        Ok(())
    })?;
    Ok(())
}

/// Serializes a grid as VTU XML.
///
/// # Errors
/// Only from the in-memory writer (practically none).
pub fn vtu_string(g: &Grid<'_>) -> std::io::Result<String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 1);
    w.write_event(quick_xml::events::Event::Decl(
        quick_xml::events::BytesDecl::new("1.0", None, None),
    ))?;
    let npts = g.points.len().to_string();
    let ncells = g.cells.len().to_string();
    w.create_element("VTKFile")
        .with_attribute(("type", "UnstructuredGrid"))
        .with_attribute(("version", "1.0"))
        .with_attribute(("byte_order", "LittleEndian"))
        .with_attribute(("header_type", "UInt64"))
        .write_inner_content(|w| {
            w.create_element("UnstructuredGrid")
                .write_inner_content(|w| {
                    w.create_element("Piece")
                        .with_attribute(("NumberOfPoints", npts.as_str()))
                        .with_attribute(("NumberOfCells", ncells.as_str()))
                        .write_inner_content(|w| {
                            w.create_element("Points").write_inner_content(|w| {
                                data_array(
                                    w,
                                    "Float64",
                                    "Points",
                                    3,
                                    &join(g.points.iter().flatten()),
                                )
                            })?;
                            w.create_element("Cells").write_inner_content(|w| {
                                data_array(
                                    w,
                                    "Int64",
                                    "connectivity",
                                    1,
                                    &join(g.cells.iter().flat_map(|c| c.1.iter())),
                                )?;
                                let mut off = 0usize;
                                let offsets = join(g.cells.iter().map(|c| {
                                    off += c.1.len();
                                    off
                                }));
                                data_array(w, "Int64", "offsets", 1, &offsets)?;
                                data_array(
                                    w,
                                    "UInt8",
                                    "types",
                                    1,
                                    &join(g.cells.iter().map(|c| c.0)),
                                )
                            })?;
                            fields(w, "PointData", &g.point_data)?;
                            fields(w, "CellData", &g.cell_data)?;
                            Ok(())
                        })?;
                    Ok(())
                })?;
            Ok(())
        })?;
    String::from_utf8(w.into_inner()).map_err(std::io::Error::other)
}

/// Serializes a `.pvd` collection of `(time, file name)` entries.
///
/// # Errors
/// Only from the in-memory writer.
pub fn pvd_string(entries: &[(f64, String)]) -> std::io::Result<String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 1);
    w.write_event(quick_xml::events::Event::Decl(
        quick_xml::events::BytesDecl::new("1.0", None, None),
    ))?;
    w.create_element("VTKFile")
        .with_attribute(("type", "Collection"))
        .with_attribute(("version", "0.1"))
        .write_inner_content(|w| {
            w.create_element("Collection").write_inner_content(|w| {
                for (t, file) in entries {
                    let ts = t.to_string();
                    w.create_element("DataSet")
                        .with_attribute(("timestep", ts.as_str()))
                        .with_attribute(("part", "0"))
                        .with_attribute(("file", file.as_str()))
                        .write_empty()?;
                }
                Ok(())
            })?;
            Ok(())
        })?;
    String::from_utf8(w.into_inner()).map_err(std::io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_counts_types_and_data() {
        let pts = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let cells = vec![vtk_cell(ElementKind::Tet4, &[0, 1, 2, 3])];
        let u = [0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.2, 0.3];
        let g = Grid {
            points: &pts,
            cells: &cells,
            point_data: vec![Field {
                name: "displacement",
                components: 3,
                values: &u,
            }],
            cell_data: vec![],
        };
        let s = vtu_string(&g).expect("xml");
        assert!(s.contains("NumberOfPoints=\"4\""));
        assert!(s.contains("NumberOfCells=\"1\""));
        assert!(s.contains("Name=\"displacement\""));
        assert!(s.contains(">10<"));
        assert!(s.contains("0.1 0.2 0.3"));
        let p = pvd_string(&[(0.5, "a.vtu".into())]).expect("xml");
        assert!(p.contains("timestep=\"0.5\""));
        assert!(p.contains("file=\"a.vtu\""));
    }

    #[test]
    fn tet10_nodes_8_and_9_swap() {
        let (t, v) = vtk_cell(ElementKind::Tet10, &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
        assert_eq!(t, 24);
        assert_eq!(v, vec![0, 1, 2, 3, 4, 5, 6, 7, 9, 8]);
    }
}
