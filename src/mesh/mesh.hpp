#pragma once
// A simulation mesh: rest positions plus the elements of one object type.
#include <string>
#include <vector>

#include "core/types.hpp"

namespace lb {

enum class MeshKind { Rods, Shell, Solid };

std::string to_string(MeshKind kind);

struct Mesh {
    MeshKind kind = MeshKind::Solid;
    /// N×3 rest positions X (m).
    MatrixX3d rest_positions;
    /// Rods: E×2 edges; shells: F×3 triangles; solids: T×4 tetrahedra (positively oriented).
    MatrixXi elements;
    /// Rods only: each rod's vertex chain, root first.
    std::vector<std::vector<int>> rods;

    Index num_vertices() const { return rest_positions.rows(); }
    /// Diagonal of the rest bounding box (m): the length scale of relative metrics.
    double bounding_box_diagonal() const;
};

/// Rod bending stencils (i−1, i, i+1) for every interior vertex of every rod (M×3).
MatrixXi rod_bending_stencils(const Mesh& mesh);

/// Hinge stencils for every interior edge of a triangle mesh (M×4): (v0, v1) the
/// shared edge, v2 the opposite vertex of the triangle containing the directed
/// edge v0→v1, v3 the opposite vertex of the other triangle.
MatrixXi shell_hinge_stencils(const MatrixXi& triangles);

/// Lumped vertex masses (kg): each element's measure × density split equally among
/// its vertices (rods: length × πr²; shells: area × thickness; solids: volume).
/// @param thickness  shell thickness (m), ignored otherwise
/// @param radius     rod radius (m), ignored otherwise
VectorXd lumped_masses(const Mesh& mesh, double density, double thickness, double radius);

} // namespace lb
