// Field files, per-face shape operators from vertex-normal differences, and the conversion of
// per-face tangent vectors to texel coordinates.
#include "texgrad/apps/vector_field.h"

#include <Eigen/Dense>
#include <array>
#include <bit>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"

namespace texgrad {
namespace {

/// Bytes of the count header and of one value of a field file.
constexpr size_t kHeaderBytes = 4;
constexpr size_t kValueBytes = 8;
/// A 3-D triangle whose Gram determinant is below this fraction of its squared trace has no
/// usable tangent plane (a sliver or a collapsed face).
constexpr double kDegenerateGram = 1e-14;

int dimensionOf(FieldBasis basis) {
  return basis == FieldBasis::Intrinsic ? 2 : 3;
}

const char* basisName(FieldBasis basis) {
  return basis == FieldBasis::Intrinsic ? "intrinsic (2 values per face)"
                                        : "extrinsic (3 values per face)";
}

uint64_t readLittleEndian(const unsigned char* bytes, size_t count) {
  uint64_t value = 0;
  for (size_t i = 0; i < count; ++i) value |= static_cast<uint64_t>(bytes[i]) << (8 * i);
  return value;
}

void writeLittleEndian(std::ofstream& out, uint64_t value, size_t count) {
  for (size_t i = 0; i < count; ++i) out.put(static_cast<char>((value >> (8 * i)) & 0xffu));
}

size_t expectedBytes(uint64_t count, int dimension) {
  return kHeaderBytes + static_cast<size_t>(count) * static_cast<size_t>(dimension) * kValueBytes;
}

/// Edge vectors (v1 - v0, v2 - v0) of face f in 3-D.
Eigen::Matrix<double, 3, 2> edges3d(const TexturedMesh& mesh, size_t f) {
  const Triangle& tri = mesh.triangles[f];
  Eigen::Matrix<double, 3, 2> e;
  e.col(0) = mesh.positions[tri[1]] - mesh.positions[tri[0]];
  e.col(1) = mesh.positions[tri[2]] - mesh.positions[tri[0]];
  return e;
}

/// Edge vectors (p1 - p0, p2 - p0) of face f in texel coordinates.
Eigen::Matrix2d edgesTexel(const TexturedMesh& mesh, const TexelGrid& grid, size_t f) {
  const Triangle& tri = mesh.uvTriangles[f];
  const Eigen::Vector2d p0 = grid.toGrid(mesh.uvs[tri[0]]);
  Eigen::Matrix2d e;
  e.col(0) = grid.toGrid(mesh.uvs[tri[1]]) - p0;
  e.col(1) = grid.toGrid(mesh.uvs[tri[2]]) - p0;
  return e;
}

bool degenerateGram(const Eigen::Matrix2d& gram) {
  const double trace = gram.trace();
  return !(trace > 0.0) || gram.determinant() <= kDegenerateGram * trace * trace;
}

/// Vertex normals with Max's weights (J. Graphics Tools 4(2), 1999): each face adds
/// (a x b) / (|a|^2 |b|^2) for its two edges a, b at the vertex, which is exact when the ring
/// lies on a sphere; area weights are not, and their O(1) error in the normal differences makes
/// the shape operator fit below inconsistent on irregular meshes. Unit; zero at vertices whose
/// faces are all degenerate.
std::vector<Eigen::Vector3d> vertexNormals(const TexturedMesh& mesh) {
  std::vector<Eigen::Vector3d> normals(mesh.positions.size(), Eigen::Vector3d::Zero());
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const Triangle& tri = mesh.triangles[f];
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d& p = mesh.positions[tri[c]];
      const Eigen::Vector3d a = mesh.positions[tri[(c + 1) % 3]] - p;
      const Eigen::Vector3d b = mesh.positions[tri[(c + 2) % 3]] - p;
      const double weight = a.squaredNorm() * b.squaredNorm();
      if (weight > 0.0) normals[tri[c]] += a.cross(b) / weight;
    }
  }
  for (auto& n : normals) {
    const double length = n.norm();
    n = length > 0.0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
  }
  return normals;
}

/// Orthonormal tangent frame (columns) of face f, or zero for a degenerate face.
Eigen::Matrix<double, 3, 2> faceFrame(const Eigen::Matrix<double, 3, 2>& e) {
  const Eigen::Vector3d normal = e.col(0).cross(e.col(1));
  Eigen::Matrix<double, 3, 2> frame = Eigen::Matrix<double, 3, 2>::Zero();
  if (degenerateGram(e.transpose() * e) || normal.norm() == 0.0) return frame;
  frame.col(0) = e.col(0).normalized();
  frame.col(1) = normal.normalized().cross(frame.col(0));
  return frame;
}

/// Shape operator dn = S dx of face f in its frame, fitted to the three edges by least squares
/// (Rusinkiewicz 2004, per-face step), returned as a 3-D tensor frame S frame^T.
Eigen::Matrix3d faceShapeTensor(const TexturedMesh& mesh, size_t f,
                                const std::vector<Eigen::Vector3d>& normals,
                                const Eigen::Matrix<double, 3, 2>& frame) {
  if (frame.isZero(0.0)) return Eigen::Matrix3d::Zero();
  const Triangle& tri = mesh.triangles[f];
  Eigen::Matrix<double, 6, 3> a = Eigen::Matrix<double, 6, 3>::Zero();
  Eigen::Matrix<double, 6, 1> b;
  for (int i = 0; i < 3; ++i) {
    const int32_t from = tri[(i + 1) % 3], to = tri[(i + 2) % 3];
    const Eigen::Vector2d edge = frame.transpose() * (mesh.positions[to] - mesh.positions[from]);
    const Eigen::Vector2d dn = frame.transpose() * (normals[to] - normals[from]);
    a.row(2 * i) << edge.x(), edge.y(), 0.0;
    a.row(2 * i + 1) << 0.0, edge.x(), edge.y();
    b(2 * i) = dn.x();
    b(2 * i + 1) = dn.y();
  }
  const Eigen::Vector3d abc = a.colPivHouseholderQr().solve(b);
  Eigen::Matrix2d s;
  s << abc(0), abc(1), abc(1), abc(2);
  return frame * s * frame.transpose();
}

/// One smoothing round: face tensors -> area-weighted vertex means -> mean of a face's corners.
void smoothTensors(const TexturedMesh& mesh, const std::vector<double>& area,
                   std::vector<Eigen::Matrix3d>& tensors) {
  std::vector<Eigen::Matrix3d> vertexSum(mesh.positions.size(), Eigen::Matrix3d::Zero());
  std::vector<double> vertexWeight(mesh.positions.size(), 0.0);
  for (size_t f = 0; f < mesh.faceCount(); ++f)
    for (int32_t v : mesh.triangles[f]) {
      vertexSum[v] += area[f] * tensors[f];
      vertexWeight[v] += area[f];
    }
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    if (area[f] == 0.0) continue;
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (int32_t v : mesh.triangles[f]) sum += vertexSum[v] / vertexWeight[v];
    tensors[f] = sum / 3.0;
  }
}

}  // namespace

FaceVectorField readFaceVectorField(const std::filesystem::path& path, FieldBasis basis,
                                    size_t faceCount) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open vector field file " + path.string());
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError("cannot read vector field file " + path.string());
  const std::string where = "vector field file " + path.string();
  if (bytes.size() < kHeaderBytes)
    throw InvalidInputError(where + " is " + std::to_string(bytes.size()) +
                            " bytes long, too short for its int32 count header");
  const auto count32 =
      static_cast<int32_t>(static_cast<uint32_t>(readLittleEndian(bytes.data(), 4)));
  if (count32 < 0)
    throw InvalidInputError(where + " has a negative vector count (" + std::to_string(count32) +
                            ")");
  const auto count = static_cast<uint64_t>(count32);
  const int dim = dimensionOf(basis);
  if (bytes.size() != expectedBytes(count, dim)) {
    const FieldBasis other =
        basis == FieldBasis::Intrinsic ? FieldBasis::Extrinsic : FieldBasis::Intrinsic;
    std::string message = where + " is " + std::to_string(bytes.size()) + " bytes long, but " +
                          std::to_string(count) + " " + basisName(basis) + " vectors take " +
                          std::to_string(expectedBytes(count, dim)) + " bytes";
    if (bytes.size() == expectedBytes(count, dimensionOf(other)))
      message += std::string("; its size fits ") + basisName(other) + " vectors" +
                 (other == FieldBasis::Intrinsic ? " (use --intrinsic)" : " (drop --intrinsic)");
    throw InvalidInputError(message);
  }
  if (count != faceCount)
    throw InvalidInputError(where + " holds " + std::to_string(count) +
                            " vectors, but the mesh has " + std::to_string(faceCount) +
                            " faces; a field needs exactly one vector per face, in face order");
  FaceVectorField field;
  field.basis = basis;
  field.vectors.assign(count, Eigen::Vector3d::Zero());
  const unsigned char* cursor = bytes.data() + kHeaderBytes;
  for (size_t f = 0; f < count; ++f)
    for (int c = 0; c < dim; ++c, cursor += kValueBytes) {
      const double value = std::bit_cast<double>(readLittleEndian(cursor, kValueBytes));
      if (!std::isfinite(value))
        throw InvalidInputError(where + ": the vector of face " + std::to_string(f) +
                                " holds a non-finite value");
      field.vectors[f](c) = value;
    }
  return field;
}

void writeFaceVectorField(const std::filesystem::path& path, const FaceVectorField& field) {
  const int dim = dimensionOf(field.basis);
  writeAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw IoError("cannot create vector field file " + temporary.string());
    writeLittleEndian(out, static_cast<uint32_t>(field.vectors.size()), kHeaderBytes);
    for (const Eigen::Vector3d& v : field.vectors)
      for (int c = 0; c < dim; ++c)
        writeLittleEndian(out, std::bit_cast<uint64_t>(v(c)), kValueBytes);
    out.close();
    if (!out) throw IoError("cannot write vector field file " + temporary.string());
  });
}

FaceVectorField extrinsicField(const TexturedMesh& mesh, const FaceVectorField& field) {
  if (field.vectors.size() != mesh.faceCount())
    throw InvalidInputError("vector field has " + std::to_string(field.vectors.size()) +
                            " vectors but the mesh has " + std::to_string(mesh.faceCount()) +
                            " faces");
  if (field.basis == FieldBasis::Extrinsic) return field;
  FaceVectorField out{FieldBasis::Extrinsic, std::vector<Eigen::Vector3d>(field.vectors.size())};
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const Triangle& t = mesh.triangles[f];
    const Eigen::Vector3d& p0 = mesh.positions[t[0]];
    out.vectors[f] = field.vectors[f].x() * (mesh.positions[t[1]] - p0) +
                     field.vectors[f].y() * (mesh.positions[t[2]] - p0);
  }
  return out;
}

std::vector<Eigen::Vector2d> fieldInTexelCoordinates(const TexturedMesh& mesh,
                                                     const TexelGrid& grid,
                                                     const FaceVectorField& field) {
  if (field.vectors.size() != mesh.faceCount())
    throw InvalidInputError("the vector field has " + std::to_string(field.vectors.size()) +
                            " vectors, but the mesh has " + std::to_string(mesh.faceCount()) +
                            " faces");
  std::vector<Eigen::Vector2d> out(mesh.faceCount(), Eigen::Vector2d::Zero());
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const Eigen::Matrix2d ep = edgesTexel(mesh, grid, f);
    if (ep.determinant() == 0.0) continue;
    Eigen::Vector2d coefficients = field.vectors[f].head<2>();
    if (field.basis == FieldBasis::Extrinsic) {
      const Eigen::Matrix<double, 3, 2> e3 = edges3d(mesh, f);
      const Eigen::Matrix2d gram = e3.transpose() * e3;
      if (degenerateGram(gram)) continue;
      coefficients = gram.ldlt().solve(e3.transpose() * field.vectors[f]);
    }
    out[f] = ep * coefficients;
  }
  return out;
}

void CurvatureOptions::validate() const {
  if (smoothingRounds < 0)
    throw InvalidInputError("curvature smoothing rounds must be >= 0, got " +
                            std::to_string(smoothingRounds));
}

PrincipalCurvatures principalCurvatures(const TexturedMesh& mesh, const CurvatureOptions& options) {
  options.validate();
  const size_t faces = mesh.faceCount();
  const std::vector<Eigen::Vector3d> normals = vertexNormals(mesh);
  std::vector<Eigen::Matrix<double, 3, 2>> frames(faces);
  std::vector<Eigen::Matrix3d> tensors(faces);
  std::vector<double> area(faces, 0.0);
  for (size_t f = 0; f < faces; ++f) {
    const Eigen::Matrix<double, 3, 2> e = edges3d(mesh, f);
    frames[f] = faceFrame(e);
    if (frames[f].isZero(0.0)) continue;
    area[f] = 0.5 * e.col(0).cross(e.col(1)).norm();
    tensors[f] = faceShapeTensor(mesh, f, normals, frames[f]);
  }
  for (size_t f = 0; f < faces; ++f)
    if (area[f] == 0.0) tensors[f].setZero();
  for (int round = 0; round < options.smoothingRounds; ++round) smoothTensors(mesh, area, tensors);

  PrincipalCurvatures out;
  out.kMajor.assign(faces, 0.0);
  out.kMinor.assign(faces, 0.0);
  out.dirMajor.assign(faces, Eigen::Vector3d::Zero());
  out.dirMinor.assign(faces, Eigen::Vector3d::Zero());
  for (size_t f = 0; f < faces; ++f) {
    if (area[f] == 0.0) continue;
    const Eigen::Matrix<double, 3, 2>& frame = frames[f];
    const Eigen::Matrix2d s = frame.transpose() * tensors[f] * frame;
    const double a = s(0, 0), b = 0.5 * (s(0, 1) + s(1, 0)), c = s(1, 1);
    const double mean = 0.5 * (a + c), radius = std::hypot(0.5 * (a - c), b);
    // Eigenvector of the larger eigenvalue of [a b; b c] at angle theta from the first axis.
    const double theta = 0.5 * std::atan2(2.0 * b, a - c);
    const Eigen::Vector3d dirLarge =
        std::cos(theta) * frame.col(0) + std::sin(theta) * frame.col(1);
    const Eigen::Vector3d dirSmall =
        -std::sin(theta) * frame.col(0) + std::cos(theta) * frame.col(1);
    const double large = mean + radius, small = mean - radius;
    const bool largeIsMajor = std::abs(large) >= std::abs(small);
    out.kMajor[f] = largeIsMajor ? large : small;
    out.kMinor[f] = largeIsMajor ? small : large;
    out.dirMajor[f] = largeIsMajor ? dirLarge : dirSmall;
    out.dirMinor[f] = largeIsMajor ? dirSmall : dirLarge;
  }
  return out;
}

FaceVectorField curvatureField(const TexturedMesh& mesh, CurvatureDirection direction,
                               const CurvatureOptions& options) {
  const PrincipalCurvatures k = principalCurvatures(mesh, options);
  FaceVectorField field;
  field.basis = FieldBasis::Extrinsic;
  field.vectors.resize(mesh.faceCount());
  for (size_t f = 0; f < mesh.faceCount(); ++f) {
    const Eigen::Vector3d& d =
        direction == CurvatureDirection::Major ? k.dirMajor[f] : k.dirMinor[f];
    field.vectors[f] = std::abs(k.kMajor[f] - k.kMinor[f]) * d;
  }
  return field;
}

}  // namespace texgrad
