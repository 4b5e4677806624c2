#pragma once
// Procedural meshes for the scenes (rod bundles, cloth grids, tet beams) and the
// readers for meshes prepared offline (OFF surfaces, tetgen .node/.ele).
// Convention: z-up, SI units (m); gravity is (0, 0, −9.81).
#include <string>

#include "mesh/mesh.hpp"

namespace lb {

// ---- generators -------------------------------------------------------------------

struct RodBundleOptions {
    int num_rods_x = 10;        ///< roots along x (≥ 1)
    int num_rods_y = 10;        ///< roots along y (≥ 1)
    int vertices_per_rod = 18;  ///< vertices of each rod including its root (≥ 2)
    double length = 0.5;        ///< rod length, root to tip (m)
    double spacing = 0.05;      ///< distance between neighbouring roots (m)
    /// Centre of the root grid: the centre of the top face of a cube of side
    /// spacing·(n−1) on which the roots sit (m).
    Vector3d center = Vector3d::Zero();
};

/// Straight rods hanging down (−z) from a regular grid of roots in the plane z = center.z.
/// Rod r = iy·num_rods_x + ix has its root at center + ((ix − (nx−1)/2)·spacing,
/// (iy − (ny−1)/2)·spacing, 0); its vertices are contiguous, root first, equally spaced.
/// elements: E×2 edges along each rod; rods: each rod's vertex chain, root first.
/// @throws Error on invalid options
Mesh make_rod_bundle(const RodBundleOptions& options);

struct ClothGridOptions {
    int nx = 16;            ///< vertices along x (≥ 2)
    int ny = 12;            ///< vertices along y (≥ 2)
    double width = 1.0;     ///< extent along x (m)
    double height = 0.75;   ///< extent along y (m)
    Vector3d origin = Vector3d::Zero();  ///< position of vertex (0, 0) (m)
};

/// A flat nx×ny vertex grid in the horizontal plane z = origin.z: vertex (i, j) has index
/// j·nx + i and position origin + (i·width/(nx−1), j·height/(ny−1), 0). Each cell is split
/// along alternating diagonals ((i + j) even: (i,j)–(i+1,j+1)); triangles are
/// counter-clockwise seen from +z (normals +z). elements: 2(nx−1)(ny−1) × 3.
Mesh make_cloth_grid(const ClothGridOptions& options);

struct TetBeamOptions {
    int nx = 10;  ///< cells along x (≥ 1)
    int ny = 2;   ///< cells along y (≥ 1)
    int nz = 2;   ///< cells along z (≥ 1)
    Vector3d size = Vector3d(1.0, 0.1, 0.1);  ///< box extents (m)
    Vector3d origin = Vector3d::Zero();       ///< min corner of the box (m)
};

/// The box [origin, origin + size] meshed with (nx+1)(ny+1)(nz+1) vertices, vertex (i, j, k)
/// at index i + (nx+1)(j + (ny+1)k). Each hex cell is split into 6 tetrahedra sharing its
/// main diagonal (Kuhn/Freudenthal subdivision), which is conforming across cells; every
/// tet is positively oriented (det Dm > 0). elements: 6·nx·ny·nz × 4.
Mesh make_tet_beam(const TetBeamOptions& options);

// ---- readers ----------------------------------------------------------------------

/// Read an OFF surface (header OFF/COFF/NOFF/CNOFF, '#' comments; per-vertex and per-face
/// extras such as colours are ignored; polygons are fan-triangulated). Returns a Shell mesh.
/// @throws IoError naming the file (and line) if it cannot be opened or is malformed
Mesh read_off_triangles(const std::string& path);

/// Read a tetgen tetrahedralisation: .node ("<#points> 3 <#attributes> <#markers>", then
/// "<index> x y z ...") and .ele ("<#tets> <4|10> <#attributes>", then "<index> n0 n1 n2 n3 ...";
/// only the corner nodes are used). Indices may start at 0 or 1. Negatively oriented tets
/// are reoriented; degenerate (zero-volume) tets are an error. Returns a Solid mesh.
/// @throws IoError naming the file (and line) if either cannot be opened or is malformed
Mesh read_tetgen(const std::string& node_path, const std::string& ele_path);

} // namespace lb
