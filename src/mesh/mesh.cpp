#include "mesh/mesh.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

#include "core/error.hpp"

namespace lb {

std::string to_string(MeshKind kind)
{
    switch (kind) {
    case MeshKind::Rods: return "rods";
    case MeshKind::Shell: return "shell";
    case MeshKind::Solid: return "solid";
    }
    return "unknown";
}

double Mesh::bounding_box_diagonal() const
{
    if (rest_positions.rows() == 0) return 0.0;
    return (rest_positions.colwise().maxCoeff() - rest_positions.colwise().minCoeff()).norm();
}

MatrixXi rod_bending_stencils(const Mesh& mesh)
{
    Index count = 0;
    for (const auto& rod : mesh.rods) {
        if (rod.size() >= 3) count += Index(rod.size()) - 2;
    }
    MatrixXi stencils(count, 3);
    Index row = 0;
    for (const auto& rod : mesh.rods) {
        for (size_t i = 1; i + 1 < rod.size(); ++i) {
            stencils.row(row++) << rod[i - 1], rod[i], rod[i + 1];
        }
    }
    return stencils;
}

MatrixXi shell_hinge_stencils(const MatrixXi& triangles)
{
    if (triangles.cols() != 3) {
        throw Error("shell_hinge_stencils: triangles must have 3 columns, got " +
                    std::to_string(triangles.cols()));
    }
    // Directed edge (a → b) of each triangle, with the triangle's vertex opposite it.
    std::map<std::pair<int, int>, int> opposite;
    for (Index f = 0; f < triangles.rows(); ++f) {
        for (int k = 0; k < 3; ++k) {
            const int a = triangles(f, k), b = triangles(f, (k + 1) % 3), c = triangles(f, (k + 2) % 3);
            if (!opposite.emplace(std::make_pair(a, b), c).second) {
                std::ostringstream msg;
                msg << "shell_hinge_stencils: directed edge " << a << "->" << b
                    << " appears in two triangles (triangle " << f
                    << "): the mesh is non-manifold or inconsistently oriented";
                throw Error(msg.str());
            }
        }
    }
    // One hinge per interior edge, emitted from the triangle holding v0→v1 with v0 < v1,
    // in triangle order (deterministic).
    std::vector<Eigen::Vector4i> hinges;
    for (Index f = 0; f < triangles.rows(); ++f) {
        for (int k = 0; k < 3; ++k) {
            const int a = triangles(f, k), b = triangles(f, (k + 1) % 3), c = triangles(f, (k + 2) % 3);
            if (a > b) continue;
            const auto other = opposite.find(std::make_pair(b, a));
            if (other == opposite.end()) continue; // boundary edge
            hinges.emplace_back(a, b, c, other->second);
        }
    }
    MatrixXi stencils(Index(hinges.size()), 4);
    for (size_t h = 0; h < hinges.size(); ++h) stencils.row(Index(h)) = hinges[h].transpose();
    return stencils;
}

VectorXd lumped_masses(const Mesh& mesh, double density, double thickness, double radius)
{
    const Index n = mesh.num_vertices();
    const MatrixX3d& X = mesh.rest_positions;
    const MatrixXi& el = mesh.elements;
    const int expected = mesh.kind == MeshKind::Rods ? 2 : mesh.kind == MeshKind::Shell ? 3 : 4;
    if (el.rows() > 0 && el.cols() != expected) {
        std::ostringstream msg;
        msg << "lumped_masses: a " << to_string(mesh.kind) << " mesh needs " << expected
            << " vertices per element, got " << el.cols();
        throw Error(msg.str());
    }
    if (el.size() > 0 && (el.minCoeff() < 0 || el.maxCoeff() >= n)) {
        throw Error("lumped_masses: element vertex index out of range");
    }
    VectorXd masses = VectorXd::Zero(n);
    for (Index e = 0; e < el.rows(); ++e) {
        // Measure of the element: length × πr², area × t, or volume (m³).
        double volume = 0.0;
        const Vector3d X0 = X.row(el(e, 0)).transpose();
        switch (mesh.kind) {
        case MeshKind::Rods:
            volume = (X.row(el(e, 1)).transpose() - X0).norm() * M_PI * radius * radius;
            break;
        case MeshKind::Shell:
            volume = 0.5 * (X.row(el(e, 1)).transpose() - X0).cross(X.row(el(e, 2)).transpose() - X0).norm() *
                     thickness;
            break;
        case MeshKind::Solid: {
            Matrix3d Dm;
            for (int a = 1; a < 4; ++a) Dm.col(a - 1) = X.row(el(e, a)).transpose() - X0;
            volume = std::abs(Dm.determinant()) / 6.0;
            break;
        }
        }
        const double share = density * volume / double(expected);
        for (int a = 0; a < expected; ++a) masses[el(e, a)] += share;
    }
    return masses;
}

} // namespace lb
