// A body cut into pieces (pieces.h, carve_scene.h): the layout's components against voxels
// touching at a face, an edge or a corner; a bar cut through by one voxel layer counted by hand;
// in a world, the pieces as separate bodies keeping mass, momentum and surviving vertices, with
// contact between them, and the same state at 1 and 2 threads.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <map>
#include <utility>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gradel/carve.h"
#include "gradel/carve_scene.h"
#include "gradel/pieces.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

bool sameBits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(Vec3)) == 0; }

// Components of the filled voxels under 26-connectivity (8 in 2D), by flood fill: per voxel its
// component's lowest voxel index (-1 empty).
std::vector<int64_t> touchingComponents(const VoxelVolume& v) {
  std::vector<int64_t> comp(v.size(), -1);
  const int kz = v.dim() == 3 ? 1 : 0;
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) {
        const size_t q = v.index(i, j, k);
        if (!v.at(i, j, k) || comp[q] >= 0) continue;
        std::vector<Int3> stack{Int3(i, j, k)};
        comp[q] = int64_t(q);
        while (!stack.empty()) {
          const Int3 p = stack.back();
          stack.pop_back();
          for (int dz = -kz; dz <= kz; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const Int3 n = p + Int3(dx, dy, dz);
                if (!v.at(n.x(), n.y(), n.z()) || comp[v.index(n.x(), n.y(), n.z())] >= 0) continue;
                comp[v.index(n.x(), n.y(), n.z())] = int64_t(q);
                stack.push_back(n);
              }
        }
      }
  return comp;
}

VoxelVolume bar(int nx, int ny, int nz, Real h) {
  VoxelVolume v(3, nx, ny, nz, h);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) v.set(i, j, k, true);
  return v;
}

std::vector<uint8_t> layerMask(const VoxelVolume& v, int x) {
  std::vector<uint8_t> m(v.size(), 0);
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j) m[v.index(x, j, k)] = 1;
  return m;
}

// A 12x4x4 box of voxels h.
ShapeSpec barShape(Real h) {
  ShapeSpec s;
  s.dims = {12, 4, 4}, s.voxelSize = h;
  Primitive box;
  box.max = Vec3(12, 4, 4);
  s.primitives = {box};
  return s;
}

Vec3 worldMomentumOf(const World& w) {
  Vec3 p = Vec3::Zero();
  for (size_t i = 0; i < w.model().numVertices(); ++i) p += w.model().mass[i] * w.state().velocities[i];
  return p;
}

Real sumOfMomentumMagnitudes(const World& w) {
  Real s = 0;
  for (size_t i = 0; i < w.model().numVertices(); ++i) s += w.model().mass[i] * w.state().velocities[i].norm();
  return s;
}

}  // namespace

// On random volumes and every layout, the layout's pieces (elements sharing a vertex) are the
// voxels' components under face, edge and corner contact, numbered largest first.
TEST(Pieces, LayoutComponentsAreVoxelsTouchingAtAFaceEdgeOrCorner) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 24; ++trial) {
    const int dim = trial % 4 == 3 ? 2 : 3;
    const int n = 6 + trial % 7;
    VoxelVolume v(dim, n, n, dim == 3 ? n : 1, 0.01);
    std::bernoulli_distribution fill(0.25 + 0.02 * (trial % 8));
    for (int k = 0; k < v.nz(); ++k)
      for (int j = 0; j < v.ny(); ++j)
        for (int i = 0; i < v.nx(); ++i) v.set(i, j, k, fill(rng));
    if (v.countFilled() == 0) continue;
    for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel}) {
      const Layout layout = buildLayout(v, kind);
      const BodyPieces p = findPieces(layout, v);
      const std::vector<int64_t> comp = touchingComponents(v);
      // The same partition: voxels share a piece exactly when they share a component.
      std::vector<int64_t> pieceOfComponent(v.size(), -1);
      std::vector<size_t> count(p.count(), 0);
      for (size_t q = 0; q < v.size(); ++q) {
        ASSERT_EQ(comp[q] < 0, p.voxelPiece[q] < 0);
        if (comp[q] < 0) continue;
        int64_t& piece = pieceOfComponent[size_t(comp[q])];
        if (piece < 0) piece = p.voxelPiece[q];
        ASSERT_EQ(piece, p.voxelPiece[q]) << "trial " << trial << " layout " << layoutKindName(kind);
        ++count[size_t(p.voxelPiece[q])];
      }
      size_t components = 0;
      for (size_t q = 0; q < v.size(); ++q) components += comp[q] == int64_t(q);
      EXPECT_EQ(p.count(), components);
      for (size_t k = 0; k < p.count(); ++k) {
        EXPECT_EQ(count[k], p.voxels[k]);
        if (k) EXPECT_GE(p.voxels[k - 1], p.voxels[k]);
      }
    }
  }
}

// A 12x4x4 bar: 24 full elements of 2x2x2 voxels (every block holds a surface voxel), whose own
// vertices are the blocks' corners, 7 x 3 x 3 = 63. The layer x = 6 removed (16 voxels), the
// carved body's layout: x in [0, 6) as 12 full blocks (vertices x in {0, 2, 4, 6}: 36); x in
// [7, 12) as 4 incomplete blocks at x = 6 holding their x = 7 cells (corners x in {7, 8}, y and z
// in 0..4: 50) and 8 full blocks at x = 8, 10 (x in {8, 10, 12}, y, z even: 27, 9 of them at
// x = 8 among the 50): 36 + 68 = 104 vertices, the 63 old ones and 41 new (x = 7, and x = 8 with
// y or z odd). It falls into those two pieces: 96 voxels (12 elements, 36 vertices) and 80 (12
// elements, 68 vertices), the pieces' own layouts the carved body's, so no vertex is new.
TEST(Pieces, BarCutThroughTheMiddleHandChecked) {
  const Real h = 0.0078125;  // 2^-7 m: voxel masses and their sums exact
  const VoxelVolume v = bar(12, 4, 4, h);
  const Layout layout = buildLayout(v, LayoutKind::Gradational);
  ASSERT_EQ(layout.numVertices(), 63u);
  ASSERT_EQ(layout.numElements(), 24u);
  auto model = std::make_shared<RestModel>(buildRestModel(layout, v, MaterialSettings{}, Vec3::Zero()));
  std::vector<Vec3> x = model->restPositions, vel(x.size());
  std::vector<Quat> rot(layout.numElements(), Quat::Identity());
  for (size_t i = 0; i < x.size(); ++i) vel[i] = Vec3(0.1 + x[i].y(), -0.2 * x[i].x(), 0.05);
  CarveInput in;
  in.volume = &v, in.layout = &layout, in.model = model.get();
  in.positions = x.data(), in.velocities = vel.data(), in.rotations = rot.data();
  const CarvedBody c = carveBody(in, layerMask(v, 6));
  EXPECT_EQ(c.removedVoxels, 16u);
  EXPECT_EQ(c.layout.numVertices(), 104u);
  EXPECT_EQ(c.newVertices, 41u);
  CarveInput cin;
  cin.volume = &c.volume, cin.layout = &c.layout, cin.model = c.model.get();
  cin.positions = c.positions.data(), cin.velocities = c.velocities.data(), cin.rotations = c.rotations.data();
  const BodyPieces found = findPieces(c.layout, c.volume);
  ASSERT_EQ(found.count(), 2u);
  EXPECT_EQ(found.voxels[0], 96u);
  EXPECT_EQ(found.voxels[1], 80u);
  const std::vector<BodyPiece> pieces = splitBody(cin);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].volume.countFilled(), 96u);
  EXPECT_EQ(pieces[1].volume.countFilled(), 80u);
  EXPECT_EQ(pieces[0].layout.numElements(), 12u);
  EXPECT_EQ(pieces[1].layout.numElements(), 12u);
  EXPECT_EQ(pieces[0].layout.numVertices(), 36u);
  EXPECT_EQ(pieces[1].layout.numVertices(), 68u);
  size_t incomplete = 0;
  for (size_t e = 0; e < pieces[1].layout.numElements(); ++e) incomplete += !pieces[1].layout.isFull(e);
  EXPECT_EQ(incomplete, 4u);
  EXPECT_TRUE(pieces[0].volume.at(5, 0, 0) && !pieces[0].volume.at(7, 0, 0));
  EXPECT_TRUE(pieces[1].volume.at(7, 0, 0) && !pieces[1].volume.at(5, 0, 0));
  // Every vertex survives with its position and velocity; masses exact: 176 voxels of rho h^3.
  Real mass = 0;
  Vec3 p = Vec3::Zero(), p0 = Vec3::Zero();
  for (const BodyPiece& piece : pieces) {
    EXPECT_EQ(piece.newVertices, 0u);
    for (size_t i = 0; i < piece.positions.size(); ++i) {
      ASSERT_NE(piece.fromVertex[i], Layout::kNoVertex);
      EXPECT_TRUE(sameBits(piece.positions[i], c.positions[piece.fromVertex[i]]));
      EXPECT_TRUE(sameBits(piece.velocities[i], c.velocities[piece.fromVertex[i]]));
      EXPECT_EQ(piece.model->mass[i], c.model->mass[piece.fromVertex[i]]);
      p += piece.model->mass[i] * piece.velocities[i];
    }
    mass += piece.model->totalMass;
  }
  for (size_t i = 0; i < c.positions.size(); ++i) p0 += c.model->mass[i] * c.velocities[i];
  // No energy at the split: the pieces' kinetic and elastic energies are the carved body's (the
  // same vertices, masses, velocities and elements).
  auto energies = [](const std::shared_ptr<const RestModel>& m, const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                     const std::vector<Quat>& q) {
    World w(m, isolated(), DomainSettings{}, {});
    w.state().positions = x, w.state().velocities = v, w.state().rotations = q;
    const Metrics k = w.metrics();
    return std::array<Real, 2>{k.kineticEnergy, k.elasticEnergy};
  };
  const std::array<Real, 2> whole = energies(c.model, c.positions, c.velocities, c.rotations);
  const std::array<Real, 2> a = energies(pieces[0].model, pieces[0].positions, pieces[0].velocities, pieces[0].rotations);
  const std::array<Real, 2> b = energies(pieces[1].model, pieces[1].positions, pieces[1].velocities, pieces[1].rotations);
  EXPECT_NEAR(a[0] + b[0], whole[0], 1e-14 * whole[0]);
  EXPECT_NEAR(a[1] + b[1], whole[1], 1e-14 * std::max(whole[1], Real(1e-30)));
  EXPECT_EQ(mass, 176 * 1000 * h * h * h);
  EXPECT_EQ(mass, model->totalMass - c.removedMass);
  EXPECT_LT((p - p0).norm(), 1e-14);
}

// A 24x12x12 box (coarse elements inside) cut at x = 9, deformed and moving at random: the pieces
// are the from-scratch layouts of their volumes and, here too, the carved body's layout
// restricted to each (no new vertex, survivors bit for bit); mass adds up exactly, momentum to
// 1e-12 of the sum of |m v|.
TEST(Pieces, CoarsePiecesAreTheirVolumesLaidOutFromScratch) {
  const Real h = 0.0078125;
  const VoxelVolume v = bar(24, 12, 12, h);
  const Layout layout = buildLayout(v, LayoutKind::Gradational);
  auto model = std::make_shared<RestModel>(buildRestModel(layout, v, MaterialSettings{}, Vec3(0.1, 0, 0)));
  std::vector<Vec3> x = model->restPositions, vel(x.size());
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (size_t i = 0; i < x.size(); ++i) x[i] += Vec3(u(rng), u(rng), u(rng)) * 1e-4, vel[i] = Vec3(u(rng), u(rng), u(rng));
  CarveInput in;
  in.volume = &v, in.layout = &layout, in.model = model.get(), in.positions = x.data(), in.velocities = vel.data();
  std::vector<uint8_t> mask = layerMask(v, 9);
  const CarvedBody c = carveBody(in, mask);
  EXPECT_GE(c.layout.numLevels(), 2);
  CarveInput cin;
  cin.volume = &c.volume, cin.layout = &c.layout, cin.model = c.model.get();
  cin.positions = c.positions.data(), cin.velocities = c.velocities.data();
  const std::vector<BodyPiece> pieces = splitBody(cin);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].volume.countFilled(), 14u * 144u);
  EXPECT_EQ(pieces[1].volume.countFilled(), 9u * 144u);
  Real mass = 0, scale = 0;
  Vec3 p = Vec3::Zero(), p0 = Vec3::Zero();
  for (const BodyPiece& piece : pieces) {
    const Layout fresh = buildLayout(piece.volume, LayoutKind::Gradational);
    EXPECT_EQ(fresh.vertices, piece.layout.vertices);
    EXPECT_EQ(fresh.elemVerts, piece.layout.elemVerts);
    EXPECT_EQ(piece.newVertices, 0u);  // the carved body's layout restricted to the piece
    for (size_t i = 0; i < piece.positions.size(); ++i) {
      p += piece.model->mass[i] * piece.velocities[i];
      if (piece.fromVertex[i] != Layout::kNoVertex) {
        EXPECT_TRUE(sameBits(piece.positions[i], c.positions[piece.fromVertex[i]]));
        EXPECT_TRUE(sameBits(piece.velocities[i], c.velocities[piece.fromVertex[i]]));
      }
    }
    mass += piece.model->totalMass;
  }
  for (size_t i = 0; i < c.positions.size(); ++i)
    p0 += c.model->mass[i] * c.velocities[i], scale += c.model->mass[i] * c.velocities[i].norm();
  EXPECT_EQ(mass, 23 * 144 * 1000 * h * h * h);
  EXPECT_LT((p - p0).norm(), 1e-12 * scale);
}

// A bar of two regions (label 1 for x < 8, label 2 of density 3000 and E 1 MPa beyond) with the
// layer x = 7 removed: each piece keeps its own region's material, and its mass is its voxels'
// at that density exactly (8 x 4 x 4 - the layer = 112 at 1000, 128 at 3000 kg/m^3).
TEST(Pieces, EachPieceKeepsItsRegionsMaterial) {
  const Real h = 0.0078125;
  VoxelVolume v(3, 16, 4, 4, h);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 16; ++i) v.setLabel(i, j, k, i < 8 ? 1 : 2);
  MaterialSettings material;
  RegionMaterial stiff;
  stiff.label = 2, stiff.density = 3000, stiff.youngsModulus = 1e6;
  material.regions = {stiff};
  const Layout layout = buildLayout(v, LayoutKind::Gradational);
  auto model = std::make_shared<RestModel>(buildRestModel(layout, v, material, Vec3::Zero()));
  std::vector<Vec3> x = model->restPositions, vel(x.size(), Vec3::Zero());
  CarveInput in;
  in.volume = &v, in.layout = &layout, in.model = model.get(), in.positions = x.data(), in.velocities = vel.data();
  const CarvedBody c = carveBody(in, layerMask(v, 7));
  CarveInput cin;
  cin.volume = &c.volume, cin.layout = &c.layout, cin.model = c.model.get();
  cin.positions = c.positions.data(), cin.velocities = c.velocities.data();
  const std::vector<BodyPiece> pieces = splitBody(cin);
  ASSERT_EQ(pieces.size(), 2u);
  // The larger piece (128 voxels) is the stiff one.
  EXPECT_EQ(pieces[0].volume.countFilled(), 128u);
  EXPECT_EQ(pieces[0].model->materialLabel, (std::vector<uint16_t>{2}));
  EXPECT_EQ(pieces[0].model->materials[0].density, 3000);
  EXPECT_EQ(pieces[0].model->totalMass, 128 * 3000 * h * h * h);
  EXPECT_EQ(pieces[1].volume.countFilled(), 112u);
  EXPECT_EQ(pieces[1].model->materialLabel, (std::vector<uint16_t>{1}));
  EXPECT_EQ(pieces[1].model->totalMass, 112 * 1000 * h * h * h);
  EXPECT_EQ(pieces[0].model->totalMass + pieces[1].model->totalMass, model->totalMass - c.removedMass);
}

namespace {

// A 12x4x4 bar of 2^-7 m voxels without gravity whose halves move towards each other; the layer
// x = 6 removed in a world: two bodies. Returns the built scene after the event.
BuiltScene cutBar(int threads, CarveEvent* event, Vec3* momentumBefore, Real* massBefore) {
  const Real h = 0.0078125;
  Scene scene;
  scene.bodies[0].shape = barShape(h);
  scene.bodies[0].name = "bar";
  scene.simulation.gravity = Vec3::Zero();
  scene.simulation.damping = 0;
  scene.simulation.threads = threads;
  BuiltScene b = buildScene(scene);
  EXPECT_EQ(b.bodies[0].volume.countFilled(), 192u);
  World& w = *b.world;
  for (size_t i = 0; i < w.state().positions.size(); ++i) {
    const Real x = w.model().restPositions[i].x();
    w.state().velocities[i] = Vec3((x < 6.5 * h ? 0.3 : -0.3) + 0.01 * x, 0.02, -0.01);
  }
  w.advanceTo(0.002);
  *momentumBefore = worldMomentumOf(w), *massBefore = w.model().totalMass;
  *event = carveSceneBody(b, 0, layerMask(b.bodies[0].volume, 6));
  return b;
}

}  // namespace

TEST(Pieces, CutBarBecomesTwoBodiesThatCollide) {
  uint64_t hashes[2] = {0, 0};
  for (int threads : {1, 2}) {
    CarveEvent e;
    Vec3 p0;
    Real m0;
    BuiltScene b = cutBar(threads, &e, &p0, &m0);
    World& w = *b.world;
    const Real h = 0.0078125;
    EXPECT_EQ(e.removedVoxels, 16u);
    ASSERT_EQ(b.numBodies(), 2u);
    EXPECT_EQ(e.pieces, (std::vector<size_t>{0, 1}));
    EXPECT_EQ(b.bodies[0].name, "bar");
    EXPECT_EQ(b.bodies[1].name, "bar-2");
    EXPECT_EQ(b.bodies[0].volume.countFilled(), 96u);
    EXPECT_EQ(b.bodies[1].volume.countFilled(), 80u);
    EXPECT_EQ(b.bodies[0].layout.numVertices(), 36u);
    EXPECT_EQ(b.bodies[1].layout.numVertices(), 68u);
    ASSERT_EQ(w.model().bodies.size(), 2u);
    EXPECT_EQ(w.model().numVertices(), 104u);
    // Mass exactly before minus the removed voxels'; momentum less the removed momentum.
    EXPECT_EQ(w.model().totalMass, m0 - e.removedMass);
    EXPECT_EQ(w.model().totalMass, 176 * 1000 * h * h * h);
    EXPECT_LT((worldMomentumOf(w) - (p0 - e.removedMomentum)).norm(), 1e-12 * sumOfMomentumMagnitudes(w));
    // The ledger stays with body 0 (the piece keeping the name), the new piece starts at zero.
    ASSERT_EQ(w.removedMaterial().size(), 2u);
    EXPECT_EQ(w.removedMaterial()[0].voxels, 16u);
    EXPECT_EQ(w.removedMaterial()[1].voxels, 0u);
    // The pieces collide through the world's body contacts: no vertex inside the other, now and
    // after they have run into each other.
    ASSERT_NE(w.bodyContacts(), nullptr);
    EXPECT_EQ(w.bodyContacts()->bodies().size(), 2u);
    // Each piece's contact surface is closed: every edge is shared by exactly two triangles.
    for (const ContactBody& cb : w.bodyContacts()->bodies()) {
      std::map<std::pair<uint32_t, uint32_t>, int> edges;
      for (const auto& t : cb.triangles)
        for (int k = 0; k < 3; ++k) ++edges[std::minmax(t[k], t[(k + 1) % 3])];
      EXPECT_FALSE(edges.empty());
      for (const auto& [e, n] : edges) ASSERT_EQ(n, 2) << e.first << "-" << e.second;
    }
    EXPECT_EQ(verticesInsideOtherBodies(w), 0u);
    size_t contacts = 0;
    while (w.time() < 0.05) {
      w.step();
      contacts += w.bodyContacts()->contacts().size();
      ASSERT_EQ(verticesInsideOtherBodies(w), 0u) << "t = " << w.time();
    }
    EXPECT_GT(contacts, 0u);
    hashes[threads - 1] = w.stateHash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

// A pin of a body that falls apart holds each piece it selects vertices of.
TEST(Pieces, PinsFollowThePieces) {
  const Real h = 0.01;
  Scene scene;
  scene.bodies[0].shape = barShape(h);
  PinSettings left, both;
  left.min = Vec3(-1e-3, -1e-3, -1e-3), left.max = Vec3(1e-3, 0.05, 0.05);  // the face x = 0
  both.min = Vec3(-1e-3, -1e-3, -1e-3), both.max = Vec3(0.13, 1e-3, 1e-3);  // the edge y = z = 0
  scene.pins = {left, both};
  BuiltScene b = buildScene(scene);
  carveSceneBody(b, 0, layerMask(b.bodies[0].volume, 6));
  ASSERT_EQ(b.numBodies(), 2u);
  const std::vector<PinSettings>& pins = b.world->pins();
  ASSERT_EQ(pins.size(), 3u);
  EXPECT_EQ(pins[0].body, 0u);
  EXPECT_EQ(pins[1].body, 0u);
  EXPECT_EQ(pins[2].body, 1u);
}

// An event the new world cannot take (it would cut away every vertex a pin holds) changes nothing:
// the scene's bodies stay those of its world, not cut.
TEST(Pieces, AnEventTheWorldRefusesLeavesTheSceneAsItWas) {
  Scene scene;
  scene.bodies[0].shape = barShape(0.01);
  PinSettings left;
  left.min = Vec3(-1e-3, -1e-3, -1e-3), left.max = Vec3(1e-3, 0.05, 0.05);  // the face x = 0
  scene.pins = {left};
  BuiltScene b = buildScene(scene);
  const uint64_t hash = b.world->stateHash();
  std::vector<uint8_t> mask = layerMask(b.bodies[0].volume, 6), face = layerMask(b.bodies[0].volume, 0);
  for (size_t q = 0; q < mask.size(); ++q) mask[q] |= face[q];
  EXPECT_THROW(carveSceneBody(b, 0, mask), InputError);
  ASSERT_EQ(b.numBodies(), 1u);
  EXPECT_EQ(b.bodies[0].volume.countFilled(), 192u);
  EXPECT_EQ(b.world->model().numVertices(), b.bodies[0].layout.numVertices());
  EXPECT_EQ(b.world->model().bodies.size(), 1u);
  EXPECT_EQ(b.world->stateHash(), hash);
  b.world->step();  // still a working world
}
