// gradel-validate: physical validity, measured (issue 5). Runs the experiments of
// include/gradel/shared/validation.h for both scalings and the three layouts and writes
// OUT/report.md, OUT/*.csv and (with matplotlib) OUT/*.png, drawn by the plotting scripts
// docs/validation/*.py (findPlotScript).
//
//   gradel-validate [--out docs/validation] [--quick] [--materials-only | --large-step-only | --poisson-only]
//
// Bars: square section a = 2 cm, length L = 8 a, density 1000 kg/m^3, E = 1e7 Pa (consistent
// scaling); paper scaling with k = 2 E h^2, which gives the finest (2-voxel) elements the
// same k_e as consistent. Resolutions: 2, 4, 8, 16 voxels across (--quick: 2, 4, 8); the voxel layout stops at 8.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <system_error>
#include <tuple>
#include <vector>

#include "gradel/shapes.h"
#include "gradel/shared/validation.h"

using namespace gradel;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

constexpr Real kWidth = 0.02, kE = 1e7, kRho = 1000, kAspect = 8;

BarSpec makeBar(Scaling scaling, LayoutKind layout, int across) {
  BarSpec b;
  b.across = across;
  b.along = int(kAspect) * across;
  b.width = kWidth;
  b.layout = layout;
  b.material.scaling = scaling;
  b.material.youngsModulus = kE;
  b.material.density = kRho;
  const Real h = b.voxelSize();
  b.material.paperK = 2 * kE * h * h;
  return b;
}

std::string fmt(double x, int prec = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", prec, x);
  return buf;
}
std::string pct(double ratio) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%+.1f %%", 100 * (ratio - 1));
  return buf;
}

// The plotting scripts are files of the source tree, docs/validation/*.py: next to the committed
// CSV files they read, so `python3 docs/validation/plots.py` redraws the committed pictures, and
// `python3 SCRIPT DIR` draws those of any output folder. A build tree runs them in place;
// `cmake --install` copies them to share/gradel/validation. The installed copy (relative to this
// binary) comes first, then the source tree this binary was built from (cmake/validate.cmake
// defines both); an empty path, with a message naming the file and the places looked in, when
// neither has it.
fs::path findPlotScript(const std::string& name) {
  std::vector<fs::path> dirs;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) dirs.push_back(exe.parent_path() / GRADEL_VALIDATION_SCRIPTS_FROM_BIN);
  dirs.push_back(GRADEL_VALIDATION_SCRIPTS_SOURCE);
  for (const fs::path& d : dirs)
    if (fs::is_regular_file(d / name, ec)) return (d / name).lexically_normal();
  std::cerr << "gradel-validate: plotting script " << name << " not found; looked for";
  for (const fs::path& d : dirs) std::cerr << ' ' << (d / name).lexically_normal().string();
  std::cerr << " (the source tree's docs/validation/" << name
            << ", which cmake --install copies to share/gradel/validation)\n";
  return {};
}

// Runs a plotting script on the CSV files in dir, which writes its pictures there; false without
// /usr/bin/python3 with matplotlib.
bool runPlot(const fs::path& script, const fs::path& dir) {
  if (!fs::exists("/usr/bin/python3")) return false;
  const std::string cmd = "/usr/bin/python3 '" + script.string() + "' '" + dir.string() + "'";
  return std::system(cmd.c_str()) == 0;
}

struct Vibration {
  Real frequency = 0;       ///< [Hz] dominant frequency of the tip.
  Real decayPerPeriod = 0;  ///< [-] amplitude ratio lost per period (0 = undamped), from the first and last thirds.
  Real energyDrift = 0;     ///< [-] max |E(t) - E(0)| / max elastic energy (total mechanical energy).
  Real nsPerStep = 0;
  Real cpuNsPerStep = 0;  ///< CPU time of the stepping thread (less sensitive to other processes than nsPerStep).
  Real dt = 0;
  size_t steps = 0;
  std::vector<Real> time, tip;
};

// Free vibration of the clamped bar released straight under gravity: the tip oscillates about
// its static sag with that amplitude.
Vibration vibrate(const BarSpec& bar, IntegratorKind kind, Real dt, Real duration, bool energy,
                  int passes = SimulationSettings{}.largeStepPasses,
                  int coarseNodes = SimulationSettings{}.largeStepCoarseNodes) {
  SimulationSettings sim;
  sim.integrator = kind;
  sim.dt = dt;
  sim.damping = 0;
  sim.largeStepPasses = passes;
  sim.largeStepCoarseNodes = coarseNodes;
  if (kind == IntegratorKind::LargeStep) sim.threads = 1;  // its sweep's cost is one thread's
  BuiltScene b = buildScene(barScene(bar, sim));
  World& w = *b.world;
  const std::vector<uint32_t> tip = tipVertices(w.model(), bar.length());
  Vibration v;
  v.dt = w.dt();
  const size_t steps = size_t(std::ceil(duration / w.dt()));
  const size_t every = std::max<size_t>(1, steps / 4000);
  Real e0 = 0, maxElastic = 0;
  if (energy) {
    const Metrics m = w.metrics();
    e0 = m.totalEnergy();
  }
  const auto t0 = Clock::now();
  double stepSeconds = 0, cpuSeconds = 0;
  auto threadCpu = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
  };
  for (size_t s = 0; s < steps; ++s) {
    const auto a = Clock::now();
    const double c = threadCpu();
    w.step();
    cpuSeconds += threadCpu() - c;
    stepSeconds += std::chrono::duration<double>(Clock::now() - a).count();
    if ((s + 1) % every == 0) {
      Real y = 0;
      for (uint32_t i : tip) y += w.state().positions[i].y() - w.model().restPositions[i].y();
      v.time.push_back(w.time());
      v.tip.push_back(y / Real(tip.size()));
      if (energy && (s + 1) % (every * 10) == 0) {
        const Metrics m = w.metrics();
        maxElastic = std::max(maxElastic, m.elasticEnergy);
        v.energyDrift = std::max(v.energyDrift, std::abs(m.totalEnergy() - e0));
      }
    }
  }
  (void)t0;
  v.steps = steps;
  v.nsPerStep = 1e9 * stepSeconds / Real(steps);
  v.cpuNsPerStep = 1e9 * cpuSeconds / Real(steps);
  if (maxElastic > 0) v.energyDrift /= maxElastic;
  v.frequency = dominantFrequency(v.tip, v.time.size() > 1 ? v.time[1] - v.time[0] : v.dt);
  // Decay: peak-to-peak amplitude in the first and last thirds, per period between their centres.
  const size_t n = v.tip.size();
  if (n >= 9 && v.frequency > 0) {
    auto range = [&](size_t a, size_t b) {
      Real lo = v.tip[a], hi = v.tip[a];
      for (size_t i = a; i < b; ++i) lo = std::min(lo, v.tip[i]), hi = std::max(hi, v.tip[i]);
      return hi - lo;
    };
    const Real r0 = range(0, n / 3), r1 = range(2 * n / 3, n);
    const Real periods = (v.time[5 * n / 6] - v.time[n / 6]) * v.frequency;
    v.decayPerPeriod = r0 > 0 && periods > 0 ? 1 - std::pow(r1 / r0, 1 / periods) : 0;
  }
  return v;
}

void writeSeries(const fs::path& file, const std::vector<std::pair<std::string, const Vibration*>>& runs) {
  std::ofstream o(file);
  o << "run,time,tip\n";
  for (const auto& [name, v] : runs)
    for (size_t i = 0; i < v->time.size(); ++i) o << name << ',' << v->time[i] << ',' << v->tip[i] << '\n';
}

// Surface displacement field of the strike scene, gradational against uniform at the same voxel
// size: vertices present in both models (same rest position), compared at several times.
struct FieldDiff {
  Real time = 0, maxDiff = 0, rmsDiff = 0, maxDisp = 0;
  Real maxDefDiff = 0, rmsDefDiff = 0,
       maxDef = 0;  ///< The same with each body's mean displacement removed (deformation only).
  size_t common = 0;
};
std::vector<FieldDiff> strikeFieldDiff(const std::string& sceneFile, Scaling scaling, std::vector<Real> times) {
  Scene base = loadScene(sceneFile);
  base.bodies[0].material.scaling = scaling;
  Scene sg = base, su = base;
  sg.bodies[0].layout = LayoutKind::Gradational;
  su.bodies[0].layout = LayoutKind::Uniform;
  BuiltScene bg = buildScene(sg), bu = buildScene(su);
  std::map<std::array<long long, 3>, uint32_t> uniformAt;
  auto key = [](const Vec3& x) {
    return std::array<long long, 3>{std::llround(x.x() * 1e6), std::llround(x.y() * 1e6), std::llround(x.z() * 1e6)};
  };
  for (size_t i = 0; i < bu.bodies[0].model->numVertices(); ++i)
    if (bu.bodies[0].model->onSurface[i]) uniformAt[key(bu.bodies[0].model->restPositions[i])] = uint32_t(i);
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (size_t i = 0; i < bg.bodies[0].model->numVertices(); ++i)
    if (bg.bodies[0].model->onSurface[i])
      if (auto it = uniformAt.find(key(bg.bodies[0].model->restPositions[i])); it != uniformAt.end())
        pairs.emplace_back(uint32_t(i), it->second);
  std::vector<FieldDiff> out;
  for (Real t : times) {
    bg.world->advanceTo(t);
    bu.world->advanceTo(t);
    FieldDiff d;
    d.time = t;
    d.common = pairs.size();
    Real sum = 0, sumDef = 0;
    Vec3 meanG = Vec3::Zero(), meanU = Vec3::Zero();
    for (auto [g, u] : pairs) {
      meanG += bg.world->state().positions[g] - bg.bodies[0].model->restPositions[g];
      meanU += bu.world->state().positions[u] - bu.bodies[0].model->restPositions[u];
    }
    meanG /= Real(std::max<size_t>(pairs.size(), 1)), meanU /= Real(std::max<size_t>(pairs.size(), 1));
    for (auto [g, u] : pairs) {
      const Vec3 dg = bg.world->state().positions[g] - bg.bodies[0].model->restPositions[g];
      const Vec3 du = bu.world->state().positions[u] - bu.bodies[0].model->restPositions[u];
      const Real diff = (dg - du).norm();
      d.maxDiff = std::max(d.maxDiff, diff);
      d.maxDisp = std::max(d.maxDisp, du.norm());
      sum += diff * diff;
      const Real def = ((dg - meanG) - (du - meanU)).norm();
      d.maxDefDiff = std::max(d.maxDefDiff, def);
      d.maxDef = std::max(d.maxDef, (du - meanU).norm());
      sumDef += def * def;
    }
    d.rmsDefDiff = std::sqrt(sumDef / Real(std::max<size_t>(pairs.size(), 1)));
    d.rmsDiff = std::sqrt(sum / Real(std::max<size_t>(pairs.size(), 1)));
    out.push_back(d);
  }
  return out;
}

// ---- 6. two materials: series and parallel bars against the rule of mixtures ----
// Bars of the same size as above, consistent scaling, E1 = kE (label 1) and E2 = 10 E1 (label 2):
// halves along the bar (series) or across its section (parallel). Writes materials.csv and
// returns the report's section; each value is checked against the 5 % target of issue 12.
std::string materialsSection(const fs::path& dir, const std::vector<int>& resolutions) {
  const Real E1 = kE, E2 = 10 * kE;
  const std::vector<LayoutKind> layouts = {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel};
  std::ofstream csv(dir / "materials.csv");
  csv << "arrangement,layout,across,elements,E_eff,E_rule,E_eff_over_rule,one_material_over_E,over_calibrated_rule\n";
  std::ostringstream md;
  md << "## 6. Two materials in one bar: series and parallel (issue 12)\n\n"
     << "The bar of section 1 made of two labels (materials per region, docs/layout.md): label 1 has E1 = " << fmt(E1)
     << " Pa, label 2 has E2 = 10 E1, same density. **Series**: the far half along the bar (x >= L/2) is "
     << "label 2, so E_rule = 2 / (1/E1 + 1/E2) = " << fmt(mixtureModulus(BarSplit::Series, E1, E2) / E1, 4)
     << " E1; **parallel**: the upper half of the section (y >= a/2), E_rule = (E1 + E2) / 2 = "
     << fmt(mixtureModulus(BarSplit::Parallel, E1, E2) / E1, 4) << " E1. Both rules are exact for the element "
     << "model's Poisson-ratio-0 material. Same stretch as section 1 (both end faces pinned, 0.1 % of L, static "
     << "equilibrium, E_eff = F L / (A dL)). Target: within 5 % of the rule. Each cell is E_eff / E_rule, and in "
     << "brackets the same against the rule applied to the moduli that the same bar of one material measures "
     << "(section 1: gradational bars are softer than E at n = 16), which isolates the effect of the border "
     << "between the materials.\n\n"
     << "| arrangement | layout |";
  for (int n : resolutions) md << " n = " << n << " |";
  md << " met |\n| --- | --- |";
  for (size_t i = 0; i <= resolutions.size(); ++i) md << " ---: |";
  md << "\n";
  std::map<std::pair<int, int>, Real> oneMaterial;  // (layout, n) -> the one-material bar's E_eff / E
  for (BarSplit split : {BarSplit::Series, BarSplit::Parallel})
    for (LayoutKind l : layouts) {
      const char* name = split == BarSplit::Series ? "series" : "parallel";
      md << "| " << name << " | " << layoutKindName(l) << " |";
      bool met = true;
      for (int n : resolutions) {
        BarSpec bar = makeBar(Scaling::Consistent, l, n);
        bar.split = split;
        RegionMaterial stiff;
        stiff.label = 2;
        stiff.youngsModulus = E2;
        stiff.density = kRho;
        bar.material.regions = {stiff};
        const Real E = stretchModulus(bar), rule = mixtureModulus(split, E1, E2);
        // The one-material bar's modulus relative to E (linear in E, so one run covers E1 and E2).
        auto [it, added] = oneMaterial.try_emplace({int(l), n}, 0.0);
        if (added) it->second = stretchModulus(makeBar(Scaling::Consistent, l, n)) / E1;
        const Real one = it->second;
        SimulationSettings sim;
        const size_t elements = buildScene(barScene(bar, sim)).bodies[0].model->numElements();
        met = met && std::abs(E / rule - 1) <= 0.05;
        csv << name << ',' << layoutKindName(l) << ',' << n << ',' << elements << ',' << E << ',' << rule << ','
            << E / rule << ',' << one << ',' << E / (rule * one) << '\n';
        md << ' ' << fmt(E / rule, 4) << " (" << fmt(E / (rule * one), 4) << ") |";
        std::cerr << "  " << name << ' ' << layoutKindName(l) << ' ' << n << ": " << E / rule << " of the rule\n";
      }
      md << ' ' << (met ? "yes" : "**no**") << " |\n";
    }
  md << "\nValues are E_eff / E_rule (E_eff / E_rule of the one-material moduli); `met`: every resolution within "
        "5 % of E_rule.\n";
  return md.str();
}

// ---- 7. Poisson's ratio (issue 29) ----
// The uniaxial experiments and the squeezed ball of include/gradel/shared/validation.h at nu = 0,
// 0.3, 0.45 and 0.49 (E = 1e5 Pa, 1000 kg/m^3), the cantilever of sections 2 and 3 at the same
// ratios, and the explicit step's dt. Writes poisson_*.csv and returns the report's section.
const std::vector<Real> kRatios = {0, 0.3, 0.45, 0.49};

MaterialSettings softMaterial(Real nu) {
  MaterialSettings m;
  m.youngsModulus = 1e5;
  m.density = kRho;
  m.poissonRatio = nu;
  return m;
}

const char* metMark(bool met) { return met ? "yes" : "**no**"; }

// Compression between frictionless walls and stretch between frictionless grips.
std::string poissonUniaxial(const fs::path& dir, bool quick) {
  std::ofstream csv(dir / "poisson_uniaxial.csv");
  csv << "experiment,integrator,layout,nu,strain,axial,lateral,ratio,volume,modulus_over_E,vertices\n";
  std::ostringstream md;
  md << "**Compression**: a box of 8^3 voxels (1 cm) pressed 2 % between two frictionless walls, free in y and z, "
        "settled with damping (the state is homogeneous: strains from the extents). **Stretch**: a bar of "
     << (quick ? 4 : 8) << " voxels across and 4x as long (section 2 cm) held by frictionless grips (the end faces' "
     << "x prescribed, y and z free) and stretched 0.1 % and 10 %; lateral strain from the mid-length section, "
        "modulus 2 U / (V eps^2) from the elastic energy U. Volume: enclosed by the deformed voxel surface over "
        "the rest one. Targets (issue 29): lateral / axial = nu within 10 %; stretch modulus within 5 % of E; "
        "volume change at 10 % stretch and nu = 0.49 within 3 %.\n\n"
     << "| experiment | integrator | layout | nu | lateral / axial | volume kept | E_eff / E | met |\n"
     << "| --- | --- | --- | ---: | ---: | ---: | ---: | --- |\n";
  auto row = [&](const char* what, IntegratorKind k, LayoutKind l, Real nu, Real strain, const UniaxialResult& r) {
    const Real ratio = r.axial != 0 ? -r.lateral / r.axial : 0;
    const bool stretch = r.modulus > 0;
    bool met = nu == 0 ? std::abs(ratio) < 0.02 : std::abs(ratio / nu - 1) <= 0.10;
    if (stretch && strain < 0.01) met = met && std::abs(r.modulus / 1e5 - 1) <= 0.05;
    if (stretch && strain >= 0.1 && nu >= 0.49) met = met && std::abs(r.volume - 1) <= 0.03;
    csv << what << ',' << integratorKindName(k) << ',' << layoutKindName(l) << ',' << nu << ',' << strain << ','
        << r.axial << ',' << r.lateral << ',' << ratio << ',' << r.volume << ',' << r.modulus / 1e5 << ','
        << r.vertices << '\n';
    md << "| " << what << " | " << integratorKindName(k) << " | " << layoutKindName(l) << " | " << nu << " | "
       << fmt(ratio, 4) << " | " << fmt(r.volume, 4) << " | " << (stretch ? fmt(r.modulus / 1e5, 4) : "") << " | "
       << metMark(met) << " |\n";
    std::cerr << "  " << what << ' ' << integratorKindName(k) << ' ' << layoutKindName(l) << " nu " << nu
              << ": ratio " << ratio << ", volume " << r.volume << "\n";
  };
  for (LayoutKind l : {LayoutKind::Uniform, LayoutKind::Gradational})
    for (Real nu : kRatios)
      row("compression 2 %", IntegratorKind::SymplecticEuler, l, nu, -0.02,
          compressBetweenWalls(softMaterial(nu), l, 8, 0.02));
  for (IntegratorKind k : {IntegratorKind::Implicit, IntegratorKind::LargeStep})
    for (Real nu : kRatios)
      row("compression 2 %", k, LayoutKind::Uniform, nu, -0.02,
          compressBetweenWalls(softMaterial(nu), LayoutKind::Uniform, 8, 0.02, k, 120));
  const int across = quick ? 4 : 8;
  for (Real strain : {0.001, 0.1})
    for (LayoutKind l : {LayoutKind::Uniform, LayoutKind::Gradational})
      for (Real nu : kRatios)
        row(strain < 0.01 ? "stretch 0.1 %" : "stretch 10 %", IntegratorKind::SymplecticEuler, l, nu, strain,
            stretchBetweenGrips(softMaterial(nu), l, across, strain));
  return md.str();
}

// The cantilever of sections 2 and 3 (consistent scaling, gradational, their finest n) at each ratio.
std::string poissonCantilever(const fs::path& dir, int n) {
  const Real sagEB = beamTipSag(kAspect * kWidth, kWidth, kRho, kE), fEB = beamFrequency(kAspect * kWidth, kWidth, kRho, kE);
  std::ofstream csv(dir / "poisson_cantilever.csv");
  csv << "nu,across,sag,sag_over_EB,frequency,frequency_over_EB,dt\n";
  std::ostringstream md;
  md << "\n**Cantilever** (sections 2 and 3: consistent scaling, gradational, n = " << n << " across, E = " << fmt(kE)
     << " Pa) at each ratio, against Euler-Bernoulli (" << fmt(sagEB * 1000) << " mm, " << fmt(fEB)
     << " Hz; beam theory has no Poisson effect in bending). Target: within 10 %.\n\n"
     << "| nu | tip sag [mm] | vs EB | first frequency [Hz] | vs EB | explicit dt [s] | met |\n"
     << "| ---: | ---: | ---: | ---: | ---: | ---: | --- |\n";
  for (Real nu : kRatios) {
    BarSpec bar = makeBar(Scaling::Consistent, LayoutKind::Gradational, n);
    bar.material.poissonRatio = nu;
    const SagResult sag = staticTipSag(bar);
    const Vibration v = vibrate(bar, IntegratorKind::SymplecticEuler, 0, 6 / fEB, false);
    const bool met = std::abs(sag.sag / sagEB - 1) <= 0.1 && std::abs(v.frequency / fEB - 1) <= 0.1;
    csv << nu << ',' << n << ',' << sag.sag << ',' << sag.sag / sagEB << ',' << v.frequency << ',' << v.frequency / fEB
        << ',' << v.dt << '\n';
    md << "| " << nu << " | " << fmt(sag.sag * 1000) << " | " << pct(sag.sag / sagEB) << " | " << fmt(v.frequency)
       << " | " << pct(v.frequency / fEB) << " | " << fmt(v.dt, 3) << " | " << metMark(met) << " |\n";
    std::cerr << "  cantilever nu " << nu << ": sag " << sag.sag / sagEB << " of EB, f " << v.frequency / fEB << "\n";
  }
  return md.str();
}

// A ball squeezed between two manipulators by 10 % and 20 % of its radius on each side; the mid-plane
// sections of the 20 % squeeze go to poisson_ball_sections.csv.
std::string poissonBall(const fs::path& dir, int size) {
  std::ofstream csv(dir / "poisson_ball.csv"), sections(dir / "poisson_ball_sections.csv");
  csv << "nu,size,squeeze,volume,width_y\n";
  sections << "nu,state,x0,y0,x1,y1,tool_x,tool_radius\n";
  std::ostringstream md;
  md << "\n**A ball squeezed** (a gradational sphere of " << size << " voxels of 5 mm, E = 1e5 Pa) between two "
     << "frictionless sphere manipulators of twice its radius, each pressing 10 % or 20 % of the radius in over "
        "0.15 s and held; no gravity, damping 30/s, 0.5 s. Target: volume kept within 3 % at nu = 0.49. The "
        "volumetric strain e_v is tr(eps) in the element's rotated frame, exact to first order: where the "
        "contact strains an element by 20 % the volume it keeps is J = 0.8 x 1.1^2 = 0.968, which is what the "
        "20 % squeeze's row shows.\n\n"
     << "| nu | volume kept, 10 % | volume kept, 20 % | width across / at rest, 20 % | met |\n"
     << "| ---: | ---: | ---: | ---: | --- |\n";
  for (Real nu : kRatios) {
    md << "| " << nu << " |";
    std::string met;
    Real width = 0;
    for (Real squeeze : {0.1, 0.2}) {
      const BallSqueeze b = squeezeBall(softMaterial(nu), size, squeeze);
      csv << nu << ',' << size << ',' << squeeze << ',' << b.volume << ',' << b.widthY << '\n';
      if (squeeze == 0.2)
        for (const auto& [state, segs] : {std::pair{"rest", &b.restSection}, std::pair{"end", &b.endSection}})
          for (const auto& q : *segs)
            sections << nu << ',' << state << ',' << q[0] << ',' << q[1] << ',' << q[2] << ',' << q[3] << ','
                     << b.toolX << ',' << b.toolRadius << '\n';
      md << ' ' << fmt(b.volume, 4) << " |";
      met += std::string(met.empty() ? "" : "; ") + (squeeze == 0.1 ? "10 %: " : "20 %: ") +
             metMark(std::abs(b.volume - 1) <= 0.03);
      width = b.widthY;
      std::cerr << "  ball nu " << nu << ", squeeze " << squeeze << ": volume " << b.volume << ", width " << b.widthY
                << "\n";
    }
    md << ' ' << fmt(width, 4) << " | " << (nu >= 0.49 ? met : "") << " |\n";
  }
  return md.str();
}

// The explicit step's dt = auto (the operator rule, stability.h) at each ratio against nu = 0.
std::string poissonTimeStep(const fs::path& dir) {
  std::ofstream csv(dir / "poisson_dt.csv");
  csv << "body,nu,dt,dt_over_nu0\n";
  std::ostringstream md;
  md << "\n**Time step**: dt = auto of the explicit step (the operator rule, stability.h, with the volumetric "
        "stiffness) against nu = 0, E = 1e5 Pa, 1 cm voxels. The explicit step pays for the compression wave as "
        "continuum theory says: sqrt((lambda + 2 mu) / E) = 1.16 / 1.95 / 4.14 at nu = 0.3 / 0.45 / 0.49.\n\n"
     << "| nu | sphere 16, gradational | box 12, uniform |\n| ---: | ---: | ---: |\n";
  std::map<std::pair<int, Real>, Real> dt;
  for (Real nu : kRatios) {
    md << "| " << nu << " |";
    for (const auto& [shape, size, layout] :
         {std::tuple{"sphere", 16, LayoutKind::Gradational}, std::tuple{"box", 12, LayoutKind::Uniform}}) {
      Scene sc;
      sc.bodies[0].shape = presetShape(shape, size, 3, 0.01);
      sc.bodies[0].layout = layout;
      sc.bodies[0].material = softMaterial(nu);
      const Real d = buildScene(sc).world->dt();
      dt[{size, nu}] = d;
      const Real ratio = d / dt.at({size, 0.0});  // kRatios starts at 0
      csv << shape << size << ',' << nu << ',' << d << ',' << ratio << '\n';
      md << ' ' << fmt(ratio, 3) << " (" << fmt(d, 3) << " s) |";
    }
    md << "\n";
  }
  return md.str();
}

// Section 7; its pictures by `script` (poisson_plot.py).
std::string poissonSection(const fs::path& dir, bool quick, const fs::path& script) {
  std::ostringstream md;
  md << "## 7. Poisson's ratio (issue 29)\n\n"
     << "`material.poisson_ratio` nu (material.h): k_e / (1 + nu) (shear modulus E / (2 (1 + nu))) plus a "
        "corotated volumetric energy kappa_e/2 e_v^2 per element, e_v = D (tr(M^T A) - tr S) / tr S (element.h), "
        "kappa_e = lambda V_e, lambda = E nu / ((1 + nu)(1 - 2 nu)): small-strain energy mu |eps|^2 + lambda/2 "
        "tr(eps)^2. Explicit rows use the symplectic step at dt = auto (the operator rule, which includes the "
        "volumetric stiffness); the implicit step holds the volume by a projective det = 1 constraint of the same "
        "small-strain stiffness.\n\n";
  std::cerr << "Poisson's ratio: uniaxial...\n";
  md << poissonUniaxial(dir, quick);
  std::cerr << "Poisson's ratio: squeezed ball...\n";
  md << poissonBall(dir, quick ? 12 : 16);
  std::cerr << "Poisson's ratio: cantilever...\n";
  md << poissonCantilever(dir, quick ? 8 : 16);  // sections 2 and 3's finest resolution
  md << poissonTimeStep(dir);
  if (runPlot(script, dir))
    md << "\n![squeezed ball](poisson_ball.png) ![measured ratio](poisson_ratio.png)\n";
  else
    std::cerr << "poisson plots: /usr/bin/python3 with matplotlib not available, section written without pictures\n";
  return md.str();
}

struct Cost {
  std::string scene, integrator;
  Real eScale = 1, dt = 0, nsPerStep = 0, rtf = 0, maxEnergy = 0;
  bool finite = true;
  size_t elements = 0, vertices = 0;
};
Cost measureCost(const std::string& sceneFile, IntegratorKind kind, Real eScale, Real duration) {
  Scene s = loadScene(sceneFile);
  s.bodies[0].material.youngsModulus *= eScale;
  s.simulation.integrator = kind;
  if (kind == IntegratorKind::Implicit) s.simulation.dt = 1.0 / 60.0;
  BuiltScene b = buildScene(s);
  World& w = *b.world;
  Cost c;
  c.scene = fs::path(sceneFile).stem().string();
  c.integrator = integratorKindName(kind);
  c.eScale = eScale;
  c.dt = w.dt();
  c.elements = w.model().numElements();
  c.vertices = w.model().numVertices();
  double seconds = 0;
  size_t steps = 0;
  const size_t every = std::max<size_t>(1, size_t(0.02 / w.dt()));
  while (w.time() < duration) {
    const auto a = Clock::now();
    w.step();
    seconds += std::chrono::duration<double>(Clock::now() - a).count();
    if (++steps % every == 0) {
      const Metrics m = w.metrics();
      const Real e = m.kineticEnergy + m.elasticEnergy;
      if (!std::isfinite(e)) {
        c.finite = false;
        break;
      }
      c.maxEnergy = std::max(c.maxEnergy, e);
    }
  }
  c.nsPerStep = 1e9 * seconds / Real(steps);
  c.rtf = w.time() / seconds;
  return c;
}

}  // namespace

// Section 4b: the large step (include/gradel/large_step.h, issue 11) on `bar`: amplitude kept and
// frequency against the explicit one (fExplicit [Hz]) over dt, CG iterations per substep and the
// coarse space's node budget; the damped sag against the static one (staticSag [m]). Writes
// large_step.csv and large_step_sweep.png (`script`, large_step_plot.py, when matplotlib is there).
std::string largeStepSection(const fs::path& dir, const BarSpec& bar, Real fExplicit, Real staticSag,
                             const fs::path& script) {
  std::cerr << "large step...\n";
  struct SweepRow {
    Real dt;
    int nodes, passes;
    Vibration v;
  };
  const SimulationSettings defaults;
  std::vector<SweepRow> sweep;
  for (int nodes : {0, 8, defaults.largeStepCoarseNodes})
    for (int passes : {5, 10, 20, 50})
      sweep.push_back(
          {1.0 / 60, nodes, passes, vibrate(bar, IntegratorKind::LargeStep, 1.0 / 60, 2.0, false, passes, nodes)});
  for (Real dt : {1.0 / 120, 1.0 / 240})
    for (int nodes : {0, defaults.largeStepCoarseNodes})
      for (int passes : {10, 20})
        sweep.push_back({dt, nodes, passes, vibrate(bar, IntegratorKind::LargeStep, dt, 2.0, false, passes, nodes)});
  {
    std::ofstream csv(dir / "large_step.csv");
    csv << "dt,coarse_nodes,passes,f,f_over_explicit,decay_per_period,us_per_step,cpu_us_per_step\n";
    for (const SweepRow& r : sweep)
      csv << r.dt << ',' << r.nodes << ',' << r.passes << ',' << r.v.frequency << ',' << r.v.frequency / fExplicit
          << ',' << r.v.decayPerPeriod << ',' << r.v.nsPerStep / 1000 << ',' << r.v.cpuNsPerStep / 1000 << '\n';
  }
  Real sag = 0;
  {
    SimulationSettings sim;
    sim.integrator = IntegratorKind::LargeStep;
    sim.dt = 1.0 / 60;
    sim.damping = 2;
    BuiltScene b = buildScene(barScene(bar, sim));
    b.world->advanceTo(3.0);
    const auto tip = tipVertices(*b.bodies[0].model, bar.length());
    for (uint32_t i : tip) sag += b.bodies[0].model->restPositions[i].y() - b.world->state().positions[i].y();
    sag /= Real(tip.size());
  }
  const bool plot = runPlot(script, dir);
  std::ostringstream md;
  md << "### Large step (include/gradel/large_step.h, issue 11)\n\n"
     << "Implicit midpoint, 2 substeps per step, Newton with `passes` CG iterations per substep, preconditioned by "
     << "the projective factor plus (coarse nodes > 0) the coarse correction of coarse_space.h (a grid of at most "
     << "that many nodes per body, 12 affine motions each). Defaults: " << defaults.largeStepPasses << " iterations, "
     << defaults.largeStepCoarseNodes << " nodes. Bar " << bar.across
     << " voxels across, released under gravity, undamped, 2 s. Targets at dt = 1/60 s: amplitude lost per period "
     << "<= 10 %, frequency within 10 % of explicit (" << fmt(fExplicit) << " Hz), static sag within 5 %. Cost: "
     << "CPU time of the one stepping thread per step (the machine may be busy; wall clock in large_step.csv).\n\n"
     << "| dt [s] | coarse nodes | CG iterations | f [Hz] | f / explicit | amplitude lost per period | CPU us/step |\n"
     << "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const SweepRow& r : sweep) {
    md << "| " << fmt(r.dt, 3) << " | " << r.nodes << " | " << r.passes << " | ";
    if (r.v.frequency > 0)
      md << fmt(r.v.frequency) << " | " << pct(r.v.frequency / fExplicit) << " | " << fmt(100 * r.v.decayPerPeriod, 3)
         << " % | ";
    else
      md << "- | - | no vibration left | ";
    md << fmt(r.v.cpuNsPerStep / 1000, 3) << " |\n";
  }
  md << "\nLarge-step dynamics at dt = 1/60 s (defaults) with damping 2/s after 3 s: sag " << fmt(sag * 1000) << " mm ("
     << pct(sag / staticSag) << " of the static sag, " << fmt(staticSag * 1000) << " mm). The stretch "
     << "test (section 1) is static and does not depend on the integrator.\n";
  if (plot) md << "\n![large step sweep](large_step_sweep.png)\n";
  return md.str();
}

int main(int argc, char** argv) {
  CLI::App app{"gradel-validate: physical validation report (docs/validation)", "gradel-validate"};
  std::string out = "docs/validation";
  bool quick = false;
  std::string scenes = "scenes";
  app.add_option("--out", out, "Output folder")->capture_default_str();
  app.add_option("--scenes", scenes, "Folder holding strike.json and grasp-two.json")->capture_default_str();
  app.add_flag("--quick", quick, "Fewer resolutions and shorter runs");
  bool materialsOnly = false;
  app.add_flag("--materials-only", materialsOnly,
               "Only the two-material section: writes materials.md and materials.csv, not report.md");
  bool largeStepOnly = false;
  app.add_flag("--large-step-only", largeStepOnly,
               "Only the large-step section on the finest bar: writes large_step.md, large_step.csv and its plot, "
               "not report.md");
  bool poissonOnly = false;
  app.add_flag("--poisson-only", poissonOnly,
               "Only the Poisson's-ratio section: writes poisson.md, poisson_*.csv and its plots, not report.md");
  CLI11_PARSE(app, argc, argv);
  // The plotting scripts this run needs, found before minutes of experiments (exit 2 without).
  bool missing = false;
  auto script = [&](const std::string& name, bool needed) {
    const fs::path path = needed ? findPlotScript(name) : fs::path();
    missing = missing || (needed && path.empty());
    return path;
  };
  const bool full = !(largeStepOnly || poissonOnly || materialsOnly);
  const fs::path reportPlot = script("plots.py", full);
  const fs::path largeStepPlot = script("large_step_plot.py", full || largeStepOnly);
  const fs::path poissonPlot = script("poisson_plot.py", full || poissonOnly);
  if (missing) return 2;
  fs::create_directories(out);
  const fs::path dir(out);
  const std::vector<int> resolutions = quick ? std::vector<int>{2, 4, 8} : std::vector<int>{2, 4, 8, 16};
  if (largeStepOnly) {
    const auto t0 = Clock::now();
    const BarSpec bar = makeBar(Scaling::Consistent, LayoutKind::Gradational, resolutions.back());
    const Vibration vx =
        vibrate(bar, IntegratorKind::SymplecticEuler, 0, 6 / beamFrequency(kAspect * kWidth, kWidth, kRho, kE), false);
    const std::string section = largeStepSection(dir, bar, vx.frequency, staticTipSag(bar).sag, largeStepPlot);
    std::ofstream(dir / "large_step.md") << "# Large step (`gradel-validate" << (quick ? " --quick" : "")
                                         << " --large-step-only`, "
                                         << fmt(std::chrono::duration<double>(Clock::now() - t0).count(), 3)
                                         << " s)\n\n"
                                         << section.substr(section.find("\n\n") + 2);
    std::cerr << "wrote " << (dir / "large_step.md").string() << "\n";
    return 0;
  }
  if (poissonOnly) {
    const auto t0 = Clock::now();
    const std::string section = poissonSection(dir, quick, poissonPlot);
    std::ofstream(dir / "poisson.md") << "# Poisson's ratio (`gradel-validate" << (quick ? " --quick" : "")
                                      << " --poisson-only`, "
                                      << fmt(std::chrono::duration<double>(Clock::now() - t0).count(), 3) << " s)\n\n"
                                      << section.substr(section.find("\n\n") + 2);
    std::cerr << "wrote " << (dir / "poisson.md").string() << "\n";
    return 0;
  }
  if (materialsOnly) {
    const auto t0 = Clock::now();
    std::cerr << "two materials...\n";
    const std::string section = materialsSection(dir, resolutions);
    std::ofstream(dir / "materials.md") << "# Two materials (`gradel-validate" << (quick ? " --quick" : "")
                                        << " --materials-only`, "
                                        << fmt(std::chrono::duration<double>(Clock::now() - t0).count(), 3) << " s)\n\n"
                                        << section.substr(section.find("\n\n") + 2);
    std::cerr << "wrote " << (dir / "materials.md").string() << "\n";
    return 0;
  }
  const std::vector<Scaling> scalings = {Scaling::Consistent, Scaling::Paper};
  const std::vector<LayoutKind> layouts = {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel};
  const int finest = resolutions.back();
  std::ostringstream md;
  const auto tStart = Clock::now();

  // ---- 1. stretch: effective modulus ----
  std::cerr << "stretch...\n";
  std::map<std::tuple<int, int, int>, Real> modulus;  // (scaling, layout, across)
  {
    std::ofstream csv(dir / "stretch.csv");
    csv << "scaling,layout,across,E_eff,E_eff_over_E\n";
    for (Scaling s : scalings)
      for (LayoutKind l : layouts)
        for (int n : resolutions) {
          const Real E = stretchModulus(makeBar(s, l, n));
          modulus[{int(s), int(l), n}] = E;
          csv << scalingName(s) << ',' << layoutKindName(l) << ',' << n << ',' << E << ',' << E / kE << '\n';
        }
  }

  // ---- 2. static sag vs Euler-Bernoulli ----
  std::cerr << "sag...\n";
  struct SagRow {
    Scaling s;
    LayoutKind l;
    int n;
    SagResult r;
    Real theoryCal, theoryNominal, massRatio;
  };
  std::vector<SagRow> sags;
  {
    std::ofstream csv(dir / "sag.csv");
    csv << "scaling,layout,across,elements,vertices,sag,theory_calibrated,theory_nominal,mass_ratio,relaxation_steps\n";
    for (Scaling s : scalings)
      for (LayoutKind l : layouts)
        for (int n : resolutions) {
          if (l == LayoutKind::Voxel && n > 8) continue;  // 32768 elements: minutes of relaxation
          const BarSpec bar = makeBar(s, l, n);
          SagRow row{s, l, n, staticTipSag(bar), 0, 0, 0};
          // Theory with the modulus the uniform layout of this scaling measures at this resolution
          // ("the material"), and the model's actual mass per length.
          SimulationSettings sim;
          BuiltScene b = buildScene(barScene(bar, sim));
          row.massRatio = b.bodies[0].model->totalMass / (kRho * kWidth * kWidth * bar.length());
          const Real Ecal = modulus[{int(s), int(LayoutKind::Uniform), n}];
          row.theoryCal = beamTipSag(bar.length(), kWidth, kRho * row.massRatio, Ecal);
          row.theoryNominal = beamTipSag(bar.length(), kWidth, kRho, kE);
          sags.push_back(row);
          csv << scalingName(s) << ',' << layoutKindName(l) << ',' << n << ',' << row.r.elements << ','
              << row.r.vertices << ',' << row.r.sag << ',' << row.theoryCal << ',' << row.theoryNominal << ','
              << row.massRatio << ',' << row.r.steps << '\n';
          std::cerr << "  " << scalingName(s) << ' ' << layoutKindName(l) << ' ' << n << ": " << row.r.sag << " (EB "
                    << row.theoryNominal << ", " << row.r.steps << " steps)\n";
        }
  }

  // ---- 3. first bending frequency, explicit (symplectic, undamped) ----
  std::cerr << "frequency...\n";
  const Real fTheory = beamFrequency(kAspect * kWidth, kWidth, kRho, kE);
  const Real periods = quick ? 4 : 6;
  struct FreqRow {
    Scaling s;
    LayoutKind l;
    int n;
    Vibration v;
    Real theoryCal;
  };
  std::vector<FreqRow> freqs;
  std::vector<Vibration> keep;
  {
    std::ofstream csv(dir / "frequency.csv");
    csv << "scaling,layout,across,f_explicit,f_theory_calibrated,f_theory_nominal,dt,steps,ns_per_step,energy_drift\n";
    for (Scaling s : scalings)
      for (LayoutKind l : layouts)
        for (int n : resolutions) {
          if (l == LayoutKind::Voxel && n > 8) continue;  // 32768 elements: minutes of explicit steps
          const BarSpec bar = makeBar(s, l, n);
          SimulationSettings sim;
          BuiltScene b = buildScene(barScene(bar, sim));
          const Real massRatio = b.bodies[0].model->totalMass / (kRho * kWidth * kWidth * bar.length());
          const Real Ecal = modulus[{int(s), int(LayoutKind::Uniform), n}];
          const Real fCal = beamFrequency(bar.length(), kWidth, kRho * massRatio, Ecal);
          FreqRow row{s, l, n, vibrate(bar, IntegratorKind::SymplecticEuler, 0, periods / fCal, true), fCal};
          csv << scalingName(s) << ',' << layoutKindName(l) << ',' << n << ',' << row.v.frequency << ',' << fCal << ','
              << fTheory << ',' << row.v.dt << ',' << row.v.steps << ',' << row.v.nsPerStep << ',' << row.v.energyDrift
              << '\n';
          std::cerr << "  " << scalingName(s) << ' ' << layoutKindName(l) << ' ' << n << ": " << row.v.frequency
                    << " Hz (EB " << fTheory << ")\n";
          row.v.time.clear(), row.v.tip.clear();
          freqs.push_back(std::move(row));
        }
  }

  // ---- 4. explicit vs implicit on the cantilever (consistent, gradational, finest) ----
  std::cerr << "explicit vs implicit...\n";
  const BarSpec bar = makeBar(Scaling::Consistent, LayoutKind::Gradational, finest);
  const Real fBar = fTheory;
  const Vibration vx = vibrate(bar, IntegratorKind::SymplecticEuler, 0, 6 / fBar, true);
  const Vibration vi60 = vibrate(bar, IntegratorKind::Implicit, 1.0 / 60, 2.0, false);
  const Vibration vi600 = vibrate(bar, IntegratorKind::Implicit, 1.0 / 600, 6 / fBar, false);
  const Vibration vi2400 = vibrate(bar, IntegratorKind::Implicit, 1.0 / 2400, 6 / fBar, false);
  writeSeries(
      dir / "tip.csv",
      {{"explicit", &vx}, {"implicit dt=1/60", &vi60}, {"implicit dt=1/600", &vi600}, {"implicit dt=1/2400", &vi2400}});
  SimulationSettings simI;
  simI.integrator = IntegratorKind::Implicit;
  simI.dt = 1.0 / 60;
  simI.damping = 2;
  Real implicitSag = 0;
  {
    BuiltScene b = buildScene(barScene(bar, simI));
    b.world->advanceTo(3.0);
    const auto tip = tipVertices(*b.bodies[0].model, bar.length());
    for (uint32_t i : tip) implicitSag += b.bodies[0].model->restPositions[i].y() - b.world->state().positions[i].y();
    implicitSag /= Real(tip.size());
  }
  const SagResult staticSag = staticTipSag(bar);

  // ---- 4b. large step (issue 11) ----
  const std::string largeStep = largeStepSection(dir, bar, vx.frequency, staticSag.sag, largeStepPlot);

  // ---- 5. gradational vs uniform: the strike scene's surface field ----
  std::cerr << "strike field...\n";
  const std::string strike = scenes + "/strike.json", grasp = scenes + "/grasp-two.json";
  std::vector<std::pair<Scaling, std::vector<FieldDiff>>> fields;
  for (Scaling s : scalings) fields.emplace_back(s, strikeFieldDiff(strike, s, {0.1, 0.13, 0.16, 0.2}));

  // ---- 6. cost per step, stability at 100x stiffness ----
  std::cerr << "cost...\n";
  std::vector<Cost> costs;
  const Real costDuration = quick ? 0.3 : 1.0;
  costs.push_back(measureCost(strike, IntegratorKind::SymplecticEuler, 1, costDuration));
  costs.push_back(measureCost(strike, IntegratorKind::Implicit, 1, costDuration));
  costs.push_back(measureCost(strike, IntegratorKind::SymplecticEuler, 100, quick ? 0.05 : 0.2));
  costs.push_back(measureCost(strike, IntegratorKind::Implicit, 100, 1.0));
  costs.push_back(measureCost(grasp, IntegratorKind::Implicit, 100, 1.5));
  costs.push_back(measureCost(strike, IntegratorKind::LargeStep, 100, 1.0));  // dt = auto: 1/60 s
  costs.push_back(measureCost(grasp, IntegratorKind::LargeStep, 100, 1.5));
  costs.push_back(measureCost(grasp, IntegratorKind::SymplecticEuler, 1, quick ? 0.3 : 1.5));

  // ---- plots ----
  const bool plots = runPlot(reportPlot, dir);
  if (!plots) std::cerr << "plots: /usr/bin/python3 with matplotlib not available, report written without pictures\n";

  // ---- report ----
  const Real sagEB = beamTipSag(kAspect * kWidth, kWidth, kRho, kE);
  md << "# Physical validation\n\n"
     << "Written by `gradel-validate" << (quick ? " --quick" : "") << "` (apps/gradel_validate.cpp; experiments in "
     << "include/gradel/shared/validation.h) in "
     << fmt(std::chrono::duration<double>(Clock::now() - tStart).count(), 3)
     << " s. Every number below is in the CSV files next to this report.\n\n"
     << "**Bar**: square section a = " << kWidth << " m, length L = " << kAspect << " a = " << kAspect * kWidth
     << " m, density " << kRho << " kg/m^3, clamped at x = 0 (every vertex of that face pinned), gravity 9.81 m/s^2. "
     << "`consistent`: E = " << fmt(kE) << " Pa. `paper`: k = 2 E h^2 (h the voxel size), so that the finest "
     << "(2-voxel) elements get the same k_e as `consistent`; every vertex has one voxel's mass. Resolutions: ";
  for (int n : resolutions) md << n << (n == finest ? "" : ", ");
  md << " voxels across (L = 8x that along). Euler-Bernoulli with E = " << fmt(kE) << " Pa: tip sag "
     << fmt(sagEB * 1000) << " mm, first frequency " << fmt(fTheory) << " Hz. The element model is a Poisson-ratio-0 "
     << "corotational material, so beam theory (which has no Poisson effect in bending either) is the right "
        "reference.\n\n";

  // ---- targets (issue 5), read off the measurements below ----
  {
    auto sagAt = [&](Scaling sc, LayoutKind l, int n) {
      for (const SagRow& r : sags)
        if (r.s == sc && r.l == l && r.n == n) return r.r.sag;
      return 0.0;
    };
    auto freqAt = [&](Scaling sc, LayoutKind l, int n) {
      for (const FreqRow& r : freqs)
        if (r.s == sc && r.l == l && r.n == n) return r.v.frequency;
      return 0.0;
    };
    // The targets are consistent scaling's; paper scaling's rows compare against the same numbers
    // (its stiffness does not follow E across element sizes, docs/decisions.md) and say so.
    bool targets = true;
    auto ratioRow = [&](const std::string& target, Real ratio, Real tolerance, const std::string& detail) {
      const bool met = std::abs(ratio - 1) <= tolerance;
      md << "| " << target << " | " << pct(ratio) << " (" << detail << ") | "
         << (targets ? (met ? "yes" : "**no**") : (met ? "within (not a target)" : "outside (not a target)")) << " |\n";
    };
    const Real sagEB0 = beamTipSag(kAspect * kWidth, kWidth, kRho, kE);
    const Real fEB0 = beamFrequency(kAspect * kWidth, kWidth, kRho, kE);
    md << "## Targets (issue 5)\n\n"
       << "Read off the sections below at the finest resolution, n = " << finest << " voxels across; the issue sets "
       << "them for `consistent` scaling (the default): those rows are the targets. `paper` scaling is measured "
       << "against the same numbers for comparison only (not targets: its k does not follow E across element "
       << "sizes). `met` is computed, not written by hand.\n\n";
    for (Scaling sc : scalings) {
      targets = sc == Scaling::Consistent;
      const Real gs = sagAt(sc, LayoutKind::Gradational, finest), us = sagAt(sc, LayoutKind::Uniform, finest);
      const Real gf = freqAt(sc, LayoutKind::Gradational, finest), uf = freqAt(sc, LayoutKind::Uniform, finest);
      md << "### `" << scalingName(sc) << "` scaling" << (targets ? ": the targets" : ": for comparison, not targets")
         << "\n\n| " << (targets ? "target" : "compared with") << " | measured | met |\n| --- | --- | --- |\n";
      ratioRow("gradational sag within 5 % of uniform", gs / us, 0.05,
               fmt(gs * 1000) + " vs " + fmt(us * 1000) + " mm");
      ratioRow("gradational first frequency within 5 % of uniform", gf / uf, 0.05, fmt(gf) + " vs " + fmt(uf) + " Hz");
      ratioRow("gradational sag within 10 % of Euler-Bernoulli", gs / sagEB0, 0.10,
               fmt(gs * 1000) + " vs " + fmt(sagEB0 * 1000) + " mm");
      ratioRow("gradational first frequency within 10 % of Euler-Bernoulli", gf / fEB0, 0.10,
               fmt(gf) + " vs " + fmt(fEB0) + " Hz");
      ratioRow("uniform sag within 10 % of Euler-Bernoulli", us / sagEB0, 0.10, fmt(us * 1000) + " mm");
      ratioRow("uniform first frequency within 10 % of Euler-Bernoulli", uf / fEB0, 0.10, fmt(uf) + " Hz");
      ratioRow("gradational bar's stretch modulus within 5 % of E (not an issue target; the cause of the sag error)",
               modulus[{int(sc), int(LayoutKind::Gradational), finest}] / kE, 0.05,
               fmt(modulus[{int(sc), int(LayoutKind::Gradational), finest}] / kE, 4) + " E");
      md << "\n";
    }
    targets = true;
    // Stability at 100x stiffness: finite throughout, and the largest energy sampled below 1000x
    // that of the explicit run at the scene's own E (a blow-up grows without bound; squeezing a
    // 100x stiffer body along the same paths may legitimately store up to ~100x the energy).
    md << "### implicit mode at dt = 1/60 s, E x100\n\n| target | measured | met |\n| --- | --- | --- |\n";
    for (const std::string& scene : {std::string("strike"), std::string("grasp-two")}) {
      const Cost* stiff = nullptr;
      const Cost* ref = nullptr;
      for (const Cost& c : costs) {
        if (c.scene == scene && c.integrator == "implicit" && c.eScale == 100) stiff = &c;
        if (c.scene == scene && c.integrator != "implicit" && c.eScale == 1) ref = &c;
      }
      if (!stiff || !ref) continue;
      const bool met = stiff->finite && std::isfinite(stiff->maxEnergy) && stiff->maxEnergy <= 1000 * ref->maxEnergy;
      md << "| " << scene << ": no NaN, energy bounded (max <= 1000x the explicit run at E x1) | "
         << (stiff->finite ? "finite" : "**NaN**") << ", max energy " << fmt(stiff->maxEnergy, 3)
         << " J (explicit, E x1: " << fmt(ref->maxEnergy, 3) << " J) | " << (met ? "yes" : "**no**") << " |\n";
    }
    md << "\n";
  }

  md << "## 1. Uniaxial stretch: the effective Young's modulus\n\n"
     << "Both end faces pinned, the far one moved by 0.1 % of L, static equilibrium (projective.h `solveStatic`, "
     << "which converges quickly here: no rotations); "
     << "E_eff = F L / (A dL) with F the elastic force on the moved face.\n\n| scaling | layout |";
  for (int n : resolutions) md << " n = " << n << " |";
  md << "\n| --- | --- |";
  for (size_t i = 0; i < resolutions.size(); ++i) md << " ---: |";
  md << "\n";
  for (Scaling s : scalings)
    for (LayoutKind l : layouts) {
      md << "| " << scalingName(s) << " | " << layoutKindName(l) << " |";
      for (int n : resolutions) md << ' ' << fmt(modulus[{int(s), int(l), n}] / kE, 4) << " E |";
      md << "\n";
    }
  md << "\n`consistent` measures E_eff = E up to the clamps' end effect; `paper` with k = 2 E h^2 matches on uniform "
     << "2-voxel elements, and its coarse elements (k_e = k / s_e) are softer, so gradational bars are softer.\n\n";

  md << "## 2. Cantilever tip sag under gravity (static) vs Euler-Bernoulli\n\n"
     << "Static equilibrium of the clamped bar by dynamic relaxation (validation.h `staticTipSag`: explicit steps, "
     << "velocities zeroed at every kinetic-energy peak, until the sag changes by < 1e-6 relative). Ratios to "
        "Euler-Bernoulli with the nominal E and density "
     << "(`EB`), and to Euler-Bernoulli with the modulus the uniform layout of that scaling measures in section 1 "
     << "and the model's real mass (`EB cal`).\n\n"
     << "| scaling | layout | n | elements | vertices | sag [mm] | / EB | / EB cal | mass / rho V | / uniform |\n"
     << "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  auto sagOf = [&](Scaling s, LayoutKind l, int n) {
    for (const SagRow& r : sags)
      if (r.s == s && r.l == l && r.n == n) return r.r.sag;
    return 0.0;
  };
  for (const SagRow& r : sags)
    md << "| " << scalingName(r.s) << " | " << layoutKindName(r.l) << " | " << r.n << " | " << r.r.elements << " | "
       << r.r.vertices << " | " << fmt(r.r.sag * 1000) << " | " << fmt(r.r.sag / r.theoryNominal, 3) << " | "
       << fmt(r.r.sag / r.theoryCal, 3) << " | " << fmt(r.massRatio, 3) << " | "
       << fmt(r.r.sag / sagOf(r.s, LayoutKind::Uniform, r.n), 3) << " |\n";
  if (plots) md << "\n![sag convergence](sag_convergence.png)\n";

  md << "\n## 3. First bending frequency (free vibration, explicit symplectic Euler, undamped)\n\n"
     << "The clamped bar is released straight under gravity and oscillates about its sag; the tip's vertical "
     << "displacement is sampled for " << periods << " periods and its spectrum (Hann window, refined DTFT peak) gives "
     << "the frequency. dt = auto (0.175 x 2 pi / omega_max, the operator rule). Energy drift: max |E(t) - E(0)| of the "
     << "total mechanical energy (with symplectic Euler's modified-energy term -dt^2/8 sum m |a|^2, which it keeps exactly on linear forces) over the run, relative to the largest elastic energy. Voxel layout at n = 8 is "
     << "skipped at n = 16 (minutes of explicit steps).\n\n"
     << "| scaling | layout | n | f [Hz] | / EB | / EB cal | / uniform | dt [s] | steps | us/step | energy drift |\n"
     << "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  auto fOf = [&](Scaling s, LayoutKind l, int n) {
    for (const FreqRow& r : freqs)
      if (r.s == s && r.l == l && r.n == n) return r.v.frequency;
    return 0.0;
  };
  for (const FreqRow& r : freqs)
    md << "| " << scalingName(r.s) << " | " << layoutKindName(r.l) << " | " << r.n << " | " << fmt(r.v.frequency)
       << " | " << fmt(r.v.frequency / fTheory, 3) << " | " << fmt(r.v.frequency / r.theoryCal, 3) << " | "
       << fmt(r.v.frequency / fOf(r.s, LayoutKind::Uniform, r.n), 3) << " | " << fmt(r.v.dt, 3) << " | " << r.v.steps
       << " | " << fmt(r.v.nsPerStep / 1000, 3) << " | " << fmt(r.v.energyDrift, 2) << " |\n";
  if (plots) md << "\n![frequency convergence](frequency_convergence.png)\n";

  md << "\n## 4. Gradational vs uniform at equal finest resolution\n\n"
     << "Sag and frequency: the `/ uniform` columns above. Strike scene (`scenes/strike.json`, 12^3 sphere, "
     << "gradational vs uniform with the same voxels): the displacement from rest of every surface vertex present "
     << "in both models, compared at several times (the manipulator touches the ball at about 0.1 s). "
     << "`deformation`: the same with each body's mean displacement removed (the two balls fly off at "
     << "slightly different speeds, which dominates the raw difference later on).\n\n"
     << "| scaling | t [s] | common surface vertices | max displacement (uniform) [mm] | max difference [mm] | RMS "
        "difference [mm] | max deformation (uniform) [mm] | deformation max diff [mm] | deformation RMS diff [mm] |\n"
     << "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto& [s, rows] : fields)
    for (const FieldDiff& d : rows)
      md << "| " << scalingName(s) << " | " << d.time << " | " << d.common << " | " << fmt(d.maxDisp * 1000) << " | "
         << fmt(d.maxDiff * 1000) << " | " << fmt(d.rmsDiff * 1000) << " | " << fmt(d.maxDef * 1000) << " | "
         << fmt(d.maxDefDiff * 1000) << " | " << fmt(d.rmsDefDiff * 1000) << " |\n";

  md << "\n## 5. Explicit vs implicit\n\n"
     << "Implicit = projective dynamics (include/gradel/projective.h), 10 local/global passes per step, same "
     << "element energy. Consistent gradational bar at n = " << finest << ":\n\n"
     << "| run | dt [s] | f [Hz] | amplitude lost per period | us/step |\n| --- | ---: | ---: | ---: | ---: |\n";
  for (const auto& [name, v] : std::vector<std::pair<std::string, const Vibration*>>{
           {"explicit (symplectic)", &vx}, {"implicit", &vi60}, {"implicit", &vi600}, {"implicit", &vi2400}})
    md << "| " << name << " | " << fmt(v->dt, 3) << " | " << fmt(v->frequency) << " | "
       << fmt(100 * v->decayPerPeriod, 3) << " % | " << fmt(v->nsPerStep / 1000, 3) << " |\n";
  md << "\nExplicit energy drift (undamped symplectic, total mechanical energy with the modified-energy term): " << fmt(vx.energyDrift, 2)
     << " of the largest elastic energy. Static sag: " << fmt(staticSag.sag * 1000)
     << " mm (dynamic relaxation); implicit dynamics at dt = 1/60 s with damping 2/s after 3 s: "
     << fmt(implicitSag * 1000) << " mm (" << pct(implicitSag / staticSag.sag) << ").\n";
  if (plots) md << "\n![tip](tip_explicit_implicit.png)\n";
  md << "\n" << largeStep;
  md << "\nCost per step and stability (one thread). `E x100` multiplies the scene's Young's modulus by 100; the "
     << "explicit integrator's dt = auto shrinks by 10x with it, the implicit and large-step ones stay at 1/60 s (the "
     << "large step's steps near a contact are projective steps, the held vertices one-sided constraints of a "
     << "filtered PCG).\n\n"
     << "| scene | integrator | E | elements | vertices | dt [s] | us/step | real-time factor | max KE+elastic [J] | "
        "finite |\n"
     << "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n";
  for (const Cost& c : costs)
    md << "| " << c.scene << " | " << c.integrator << " | x" << c.eScale << " | " << c.elements << " | " << c.vertices
       << " | " << fmt(c.dt, 3) << " | " << fmt(c.nsPerStep / 1000, 3) << " | " << fmt(c.rtf, 3) << " | "
       << fmt(c.maxEnergy, 3) << " | " << (c.finite ? "yes" : "**no**") << " |\n";

  std::cerr << "two materials...\n";
  md << "\n" << materialsSection(dir, resolutions);
  md << "\n" << poissonSection(dir, quick, poissonPlot);

  std::ofstream(dir / "report.md") << md.str();
  std::cerr << "wrote " << (dir / "report.md").string() << "\n";
  return 0;
}
