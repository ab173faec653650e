// A cloth falls onto a sphere and a second cloth below it, stepped as a simulator
// with a line search would: each step proposes a motion, takes the collision-free step
// size of it (cstreams::MeshCcd), and stops the vertices that the active set within dhat
// (cstreams::MeshProximity) finds touching. Every array is a simulator's Eigen matrix.
//
//   backtracking_cloth [--steps N] [--out FOLDER] [device filter]
//
// With --out, writes every frame as FOLDER/frame_NNN.ply (one mesh: the falling cloth,
// the sphere, the cloth below), so that `cstreams reference FOLDER/frame_*.ply` can check
// that no step the simulation took collides.
#include <cstreams/devices.hpp>
#include <cstreams/io/mesh_io.hpp>
#include <cstreams/runtime/context.hpp>
#include <cstreams/scenes/shapes.hpp>
#include <cstreams/simulation/mesh_ccd.hpp>
#include <cstreams/simulation/mesh_proximity.hpp>

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace {

struct Arguments {
  int steps = 60;
  std::string out, device;
};

Arguments parse(int argc, char** argv)
{
  Arguments a;
  a.device = cstreams::filter_from_environment();
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--steps") && i + 1 < argc) a.steps = std::stoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--out") && i + 1 < argc) a.out = argv[++i];
    else a.device = argv[i];
  }
  return a;
}

// The falling cloth (its vertices first), the sphere and the cloth below, as one mesh.
struct World {
  cstreams::Mesh mesh;
  Eigen::Index falling = 0;  // the falling cloth's vertices: rows 0 .. falling - 1
};

World make_world()
{
  using cstreams::Vec3;
  World w;
  w.mesh = cstreams::scenes::sheet(24, 24, 1.2, 1.2);
  for (Vec3& p : w.mesh.positions) p += Vec3(-0.6, -0.6, 0.75);
  w.falling = Eigen::Index(w.mesh.positions.size());
  cstreams::scenes::append(w.mesh, cstreams::scenes::icosphere(2, 0.35, Vec3(0.1, 0.05, 0.2)));
  cstreams::Mesh below = cstreams::scenes::sheet(16, 16, 2.0, 2.0);
  for (Vec3& p : below.positions) p += Vec3(-1.0, -1.0, -0.2);
  cstreams::scenes::append(w.mesh, below);
  return w;
}

Eigen::MatrixXd matrix_of(const std::vector<cstreams::Vec3>& x)
{
  Eigen::MatrixXd V(Eigen::Index(x.size()), 3);
  for (std::size_t i = 0; i < x.size(); ++i) V.row(Eigen::Index(i)) = x[i].transpose();
  return V;
}

void write_frame(const std::string& folder, int frame, const cstreams::Mesh& topology, const Eigen::MatrixXd& V)
{
  cstreams::Mesh m;
  m.faces = topology.faces;
  for (Eigen::Index i = 0; i < V.rows(); ++i) m.positions.emplace_back(V(i, 0), V(i, 1), V(i, 2));
  char name[32];
  std::snprintf(name, sizeof name, "/frame_%03d.ply", frame);
  cstreams::write_ply(folder + name, m);
}

}  // namespace

int main(int argc, char** argv)
try {
  const Arguments args = parse(argc, argv);
  cstreams::runtime::Context device(args.device);
  const World world = make_world();
  Eigen::MatrixXi F(Eigen::Index(world.mesh.faces.size()), 3);
  for (std::size_t f = 0; f < world.mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) F(Eigen::Index(f), k) = int(world.mesh.faces[f][std::size_t(k)]);
  Eigen::MatrixXd V = matrix_of(world.mesh.positions);

  cstreams::MeshCcd ccd(device, cstreams::CollisionMesh(V, F));
  cstreams::MeshProximity proximity(device, cstreams::CollisionMesh(V, F));
  const double dt = 0.02, gravity = -9.8, min_distance = 1e-3, dhat = 1e-2;
  Eigen::MatrixXd velocity = Eigen::MatrixXd::Zero(V.rows(), 3);
  std::vector<bool> stopped(std::size_t(world.falling), false);
  std::printf("device: %s; %zu vertices, %zu faces\n", device.device().name.c_str(), std::size_t(V.rows()),
              world.mesh.faces.size());
  if (!args.out.empty()) write_frame(args.out, 0, world.mesh, V);

  for (int step = 1; step <= args.steps; ++step) {
    for (Eigen::Index v = 0; v < world.falling; ++v)
      if (!stopped[std::size_t(v)]) velocity(v, 2) += gravity * dt;
    const Eigen::MatrixXd proposed = V + dt * velocity;
    // The line search: as far along the proposed motion as stays min_distance apart.
    const double alpha = ccd.collision_free_stepsize(V, proposed, min_distance);
    V += alpha * (proposed - V);
    // The active set: vertices of the falling cloth closer than dhat to anything stop.
    std::size_t newly = 0;
    const auto& pairs = proximity.close_pairs(V, dhat);
    for (const cstreams::ClosePair& p : pairs)
      for (const std::uint32_t v : p.v)
        if (v < world.falling && !stopped[v]) {
          stopped[v] = true;
          velocity.row(v).setZero();
          ++newly;
        }
    std::printf("step %3d: step size %.4f, %5zu pairs within dhat, %3zu vertices stopped\n", step, alpha,
                pairs.size(), newly);
    if (!args.out.empty()) write_frame(args.out, step, world.mesh, V);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "backtracking_cloth: %s\n", e.what());
  return 1;
}
