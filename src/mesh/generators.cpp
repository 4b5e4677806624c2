#include "mesh/generators.hpp"

#include <Eigen/LU>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/limits.hpp"

namespace lb {
namespace {

void require(bool ok, const std::string& message)
{
    if (!ok) throw Error(message);
}

} // namespace

// ---- generators -------------------------------------------------------------------

Mesh make_rod_bundle(const RodBundleOptions& o)
{
    require(o.num_rods_x >= 1 && o.num_rods_y >= 1, "make_rod_bundle: num_rods_x and num_rods_y must be >= 1");
    require(o.vertices_per_rod >= 2, "make_rod_bundle: vertices_per_rod must be >= 2");
    require(o.length > 0.0, "make_rod_bundle: length must be positive");
    require(o.spacing > 0.0 || (o.num_rods_x == 1 && o.num_rods_y == 1),
            "make_rod_bundle: spacing must be positive");

    const int num_rods = o.num_rods_x * o.num_rods_y;
    const int nv = o.vertices_per_rod;
    Mesh mesh;
    mesh.kind = MeshKind::Rods;
    mesh.rest_positions.resize(Index(num_rods) * nv, 3);
    mesh.elements.resize(Index(num_rods) * (nv - 1), 2);
    mesh.rods.resize(size_t(num_rods));
    const double segment = o.length / double(nv - 1);
    for (int iy = 0; iy < o.num_rods_y; ++iy) {
        for (int ix = 0; ix < o.num_rods_x; ++ix) {
            const int r = iy * o.num_rods_x + ix;
            const Vector3d root = o.center + Vector3d((ix - 0.5 * (o.num_rods_x - 1)) * o.spacing,
                                                      (iy - 0.5 * (o.num_rods_y - 1)) * o.spacing, 0.0);
            auto& rod = mesh.rods[size_t(r)];
            rod.resize(size_t(nv));
            for (int k = 0; k < nv; ++k) {
                const int v = r * nv + k;
                rod[size_t(k)] = v;
                mesh.rest_positions.row(v) = (root - Vector3d(0.0, 0.0, k * segment)).transpose();
                if (k > 0) mesh.elements.row(Index(r) * (nv - 1) + k - 1) << v - 1, v;
            }
        }
    }
    return mesh;
}

Mesh make_cloth_grid(const ClothGridOptions& o)
{
    require(o.nx >= 2 && o.ny >= 2, "make_cloth_grid: nx and ny must be >= 2");
    require(o.width > 0.0 && o.height > 0.0, "make_cloth_grid: width and height must be positive");
    Mesh mesh;
    mesh.kind = MeshKind::Shell;
    mesh.rest_positions.resize(Index(o.nx) * o.ny, 3);
    for (int j = 0; j < o.ny; ++j) {
        for (int i = 0; i < o.nx; ++i) {
            mesh.rest_positions.row(Index(j) * o.nx + i) =
                (o.origin + Vector3d(i * o.width / (o.nx - 1), j * o.height / (o.ny - 1), 0.0)).transpose();
        }
    }
    mesh.elements.resize(2 * Index(o.nx - 1) * (o.ny - 1), 3);
    Index f = 0;
    for (int j = 0; j + 1 < o.ny; ++j) {
        for (int i = 0; i + 1 < o.nx; ++i) {
            const int v00 = j * o.nx + i, v10 = v00 + 1, v01 = v00 + o.nx, v11 = v01 + 1;
            if ((i + j) % 2 == 0) {
                mesh.elements.row(f++) << v00, v10, v11;
                mesh.elements.row(f++) << v00, v11, v01;
            } else {
                mesh.elements.row(f++) << v00, v10, v01;
                mesh.elements.row(f++) << v10, v11, v01;
            }
        }
    }
    return mesh;
}

Mesh make_tet_beam(const TetBeamOptions& o)
{
    require(o.nx >= 1 && o.ny >= 1 && o.nz >= 1, "make_tet_beam: nx, ny and nz must be >= 1");
    require((o.size.array() > 0.0).all(), "make_tet_beam: size must be positive along every axis");
    const int sx = o.nx + 1, sy = o.ny + 1, sz = o.nz + 1;
    auto vertex = [&](int i, int j, int k) { return i + sx * (j + sy * k); };

    Mesh mesh;
    mesh.kind = MeshKind::Solid;
    mesh.rest_positions.resize(Index(sx) * sy * sz, 3);
    for (int k = 0; k < sz; ++k) {
        for (int j = 0; j < sy; ++j) {
            for (int i = 0; i < sx; ++i) {
                mesh.rest_positions.row(vertex(i, j, k)) =
                    (o.origin + Vector3d(o.size.x() * i / o.nx, o.size.y() * j / o.ny, o.size.z() * k / o.nz))
                        .transpose();
            }
        }
    }

    // Kuhn subdivision of the unit cube: for each permutation p of the axes, the path
    // 000 → e_p0 → e_p0 + e_p1 → 111. Its orientation is the permutation's sign; odd ones
    // swap their middle vertices so every tet has det Dm > 0.
    static const std::array<std::array<int, 3>, 6> kPermutations = {
        {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}}};
    std::vector<std::array<Eigen::Vector3i, 4>> corners;
    for (const auto& p : kPermutations) {
        std::array<Eigen::Vector3i, 4> c;
        c[0] = Eigen::Vector3i::Zero();
        c[1] = c[0];
        c[1][p[0]] = 1;
        c[2] = c[1];
        c[2][p[1]] = 1;
        c[3] = Eigen::Vector3i::Ones();
        Matrix3d Dm;
        for (int a = 1; a < 4; ++a) Dm.col(a - 1) = (c[a] - c[0]).cast<double>();
        if (Dm.determinant() < 0.0) std::swap(c[1], c[2]);
        corners.push_back(c);
    }

    mesh.elements.resize(6 * Index(o.nx) * o.ny * o.nz, 4);
    Index t = 0;
    for (int k = 0; k < o.nz; ++k) {
        for (int j = 0; j < o.ny; ++j) {
            for (int i = 0; i < o.nx; ++i) {
                for (const auto& c : corners) {
                    for (int a = 0; a < 4; ++a) {
                        mesh.elements(t, a) = vertex(i + c[a].x(), j + c[a].y(), k + c[a].z());
                    }
                    ++t;
                }
            }
        }
    }
    return mesh;
}

// ---- readers ----------------------------------------------------------------------

namespace {

/// Whitespace-separated tokens of a text file with '#' comments, tracking line numbers
/// so that every error names the file and line.
class TokenReader {
public:
    TokenReader(const std::string& path, const std::string& what) : m_path(path), m_in(path)
    {
        if (!m_in) throw IoError("cannot open " + what + " file '" + path + "'");
        std::error_code ec;
        m_size = std::filesystem::file_size(path, ec);
        if (ec) m_size = static_cast<std::uintmax_t>(-1);  // not a regular file: only the limit applies
    }

    /// Check a header's record count before anything is allocated for it: at most `max`,
    /// and no more records than the file can hold, each `tokens` whitespace-separated
    /// tokens on its own line (at least 2·tokens bytes). Fails naming the line and count.
    void check_count(long count, const std::string& what, int tokens, long long max) const
    {
        if (count > max)
            fail("the header declares " + std::to_string(count) + " " + what + "; at most " + std::to_string(max) +
                 " are supported");
        const std::uintmax_t needed = std::uintmax_t(count) * std::uintmax_t(2 * tokens) - 1;
        if (count > 0 && needed > m_size)
            fail("the header declares " + std::to_string(count) + " " + what + ", but the file has only " +
                 std::to_string(m_size) + " bytes (" + std::to_string(count) + " " + what + " need at least " +
                 std::to_string(needed) + ")");
    }

    /// Next token (possibly on a later line); false at end of file.
    bool next(std::string& token)
    {
        while (true) {
            if (m_line_stream >> token) return true;
            std::string line;
            if (!std::getline(m_in, line)) return false;
            ++m_line;
            const auto hash = line.find('#');
            if (hash != std::string::npos) line.erase(hash);
            m_line_stream.clear();
            m_line_stream.str(line);
        }
    }

    /// Discard what is left of the current line (optional per-line extras).
    void skip_rest_of_line()
    {
        m_line_stream.clear();
        m_line_stream.str("");
    }

    std::string expect(const std::string& what)
    {
        std::string token;
        if (!next(token)) fail("unexpected end of file, expected " + what);
        return token;
    }

    long read_int(const std::string& what)
    {
        const std::string token = expect(what);
        errno = 0;
        char* end = nullptr;
        const long value = std::strtol(token.c_str(), &end, 10);
        if (end == token.c_str() || *end != '\0' || errno != 0) {
            fail("expected " + what + " (an integer), got '" + token + "'");
        }
        return value;
    }

    double read_double(const std::string& what)
    {
        const std::string token = expect(what);
        errno = 0;
        char* end = nullptr;
        const double value = std::strtod(token.c_str(), &end);
        if (end == token.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(value)) {
            fail("expected " + what + " (a finite number), got '" + token + "'");
        }
        return value;
    }

    [[noreturn]] void fail(const std::string& message) const
    {
        std::ostringstream msg;
        msg << m_path << ":" << m_line << ": " << message;
        throw IoError(msg.str());
    }

private:
    std::string m_path;
    std::ifstream m_in;
    std::istringstream m_line_stream;
    long m_line = 0;
    std::uintmax_t m_size = 0;  ///< bytes in the file
};

bool is_off_header(const std::string& token)
{
    return token == "OFF" || token == "COFF" || token == "NOFF" || token == "CNOFF" || token == "NCOFF" ||
           token == "STOFF" || token == "STCOFF" || token == "STNOFF" || token == "STCNOFF";
}

} // namespace

Mesh read_off_triangles(const std::string& path)
{
    TokenReader in(path, "OFF");
    const std::string header = in.expect("the OFF header");
    if (!is_off_header(header)) in.fail("expected an 'OFF' header, got '" + header + "'");
    const long nv = in.read_int("the vertex count");
    const long nf = in.read_int("the face count");
    in.read_int("the edge count");
    if (nv <= 0 || nf < 0) in.fail("invalid vertex/face counts");
    in.check_count(nv, "vertices", 3, kMaxMeshVertices);
    in.check_count(nf, "faces", 4, kMaxMeshElements);
    in.skip_rest_of_line();

    Mesh mesh;
    mesh.kind = MeshKind::Shell;
    mesh.rest_positions.resize(nv, 3);
    for (long v = 0; v < nv; ++v) {
        for (int c = 0; c < 3; ++c) {
            mesh.rest_positions(v, c) = in.read_double("vertex " + std::to_string(v) + " coordinate");
        }
        in.skip_rest_of_line();
    }
    std::vector<Eigen::Vector3i> triangles;
    triangles.reserve(size_t(nf));
    for (long f = 0; f < nf; ++f) {
        const long n = in.read_int("the vertex count of face " + std::to_string(f));
        if (n < 3) in.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " vertices (need >= 3)");
        if (n > nv) in.fail("face " + std::to_string(f) + " has " + std::to_string(n) + " vertices, more than the " +
                            std::to_string(nv) + " of the mesh");
        std::vector<int> polygon(static_cast<size_t>(n));
        for (long k = 0; k < n; ++k) {
            const long index = in.read_int("a vertex index of face " + std::to_string(f));
            if (index < 0 || index >= nv) {
                in.fail("face " + std::to_string(f) + " references vertex " + std::to_string(index) +
                        ", but there are " + std::to_string(nv) + " vertices");
            }
            polygon[size_t(k)] = int(index);
        }
        in.skip_rest_of_line();
        for (long k = 1; k + 1 < n; ++k) triangles.emplace_back(polygon[0], polygon[size_t(k)], polygon[size_t(k + 1)]);
    }
    mesh.elements.resize(Index(triangles.size()), 3);
    for (size_t f = 0; f < triangles.size(); ++f) mesh.elements.row(Index(f)) = triangles[f].transpose();
    return mesh;
}

Mesh read_tetgen(const std::string& node_path, const std::string& ele_path)
{
    Mesh mesh;
    mesh.kind = MeshKind::Solid;

    TokenReader nodes(node_path, "tetgen .node");
    const long nv = nodes.read_int("the point count");
    const long dim = nodes.read_int("the dimension");
    if (nv <= 0) nodes.fail("the point count must be positive");
    if (dim != 3) nodes.fail("expected dimension 3, got " + std::to_string(dim));
    nodes.check_count(nv, "points", 4, kMaxMeshVertices);
    nodes.skip_rest_of_line();
    mesh.rest_positions.resize(nv, 3);
    long base = 0;
    for (long v = 0; v < nv; ++v) {
        const long index = nodes.read_int("a point index");
        if (v == 0) {
            if (index != 0 && index != 1) nodes.fail("point indices must start at 0 or 1, got " + std::to_string(index));
            base = index;
        } else if (index != base + v) {
            nodes.fail("expected point index " + std::to_string(base + v) + ", got " + std::to_string(index));
        }
        for (int c = 0; c < 3; ++c) mesh.rest_positions(v, c) = nodes.read_double("a point coordinate");
        nodes.skip_rest_of_line();
    }

    TokenReader ele(ele_path, "tetgen .ele");
    const long nt = ele.read_int("the tetrahedron count");
    const long per_tet = ele.read_int("the nodes per tetrahedron");
    if (nt <= 0) ele.fail("the tetrahedron count must be positive");
    if (per_tet != 4 && per_tet != 10) ele.fail("expected 4 or 10 nodes per tetrahedron, got " + std::to_string(per_tet));
    ele.check_count(nt, "tetrahedra", 1 + int(per_tet), kMaxMeshElements);
    ele.skip_rest_of_line();
    mesh.elements.resize(nt, 4);
    for (long t = 0; t < nt; ++t) {
        ele.read_int("a tetrahedron index");
        for (int a = 0; a < 4; ++a) {
            const long node = ele.read_int("a node index");
            if (node - base < 0 || node - base >= nv) {
                ele.fail("tetrahedron " + std::to_string(t) + " references node " + std::to_string(node) +
                         ", outside the " + std::to_string(nv) + " points of '" + node_path + "'");
            }
            mesh.elements(t, a) = int(node - base);
        }
        Matrix3d Dm;
        for (int a = 1; a < 4; ++a) {
            Dm.col(a - 1) = (mesh.rest_positions.row(mesh.elements(t, a)) -
                             mesh.rest_positions.row(mesh.elements(t, 0))).transpose();
        }
        const double det = Dm.determinant();
        if (det == 0.0 || !std::isfinite(det)) ele.fail("tetrahedron " + std::to_string(t) + " is degenerate (zero volume)");
        if (det < 0.0) std::swap(mesh.elements(t, 1), mesh.elements(t, 2));
        ele.skip_rest_of_line();
    }
    return mesh;
}

} // namespace lb
