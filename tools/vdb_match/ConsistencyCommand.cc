/// @file ConsistencyCommand.cc
/// @brief `vdb_match consistency PHI.vdb PSI.vdb --source M1 --target M2`: the inverse
///        consistency and matching figures of a pair of deformations (paper tab:inverseError),
///        as a table or one JSON object (docs/cli.md).
#include "Cli.h"
#include "CliSupport.h"

#include <vdbmatch/eval/Consistency.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/ShapeIO.h>

#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

struct ConsistencyCliOptions
{
    std::string phi, psi, source, target, sourceGrid, targetGrid;
    int stride = eval::ConsistencyOptions().stride;
    int distanceLevel = 0;
    int threads = 0;
    bool json = false;
};

std::vector<Option<ConsistencyCliOptions>>
consistencyOptionTable()
{
    using O = ConsistencyCliOptions;
    // clang-format off
    return {
        {"--source", "M1", "Input",
         "the source shape of PHI (any shape file of match; required)",
         [](O& o, const std::string& v) { o.source = v; }},
        {"--target", "M2", "Input",
         "the target shape of PHI, source of PSI (required)",
         [](O& o, const std::string& v) { o.target = v; }},
        {"--source-grid", "NAME", "Input", "grid to read from a .vdb M1 (default: its only float grid)",
         [](O& o, const std::string& v) { o.sourceGrid = v; }},
        {"--target-grid", "NAME", "Input", "grid to read from a .vdb M2",
         [](O& o, const std::string& v) { o.targetGrid = v; }},
        {"--stride", "N", "Measurement",
         "sample Omega every N nodes of the finer deformation grid, >= 1 (default 1)",
         [](O& o, const std::string& v) { o.stride = parseInt("--stride", v); }},
        {"--distance-level", "L", "Measurement",
         "level 2^-L of the distance grids of the residuals (default: one finer than the "
         "deformations, 7..8 in 3D, 9..11 in 2D)",
         [](O& o, const std::string& v) { o.distanceLevel = parseInt("--distance-level", v); }},
        {"--json", nullptr, "Output", "print one JSON object instead of the table",
         [](O& o, const std::string&) { o.json = true; }},
        {"--threads", "N", "Execution", "number of threads, 0 = all cores (default 0)",
         [](O& o, const std::string& v) { o.threads = parseThreads(v); }},
    };
    // clang-format on
}

ConsistencyCliOptions
parseConsistencyOptions(int argc, const char* const* argv, int first)
{
    ConsistencyCliOptions o;
    const std::vector<std::string> positional =
        parseOptions(consistencyOptionTable(), argc, argv, first, o);
    if (positional.size() != 2) {
        throw UsageError("consistency expects PHI.vdb PSI.vdb, got " +
                         std::to_string(positional.size()) + " file argument(s)");
    }
    o.phi = positional[0];
    o.psi = positional[1];
    if (o.source.empty() || o.target.empty()) {
        throw UsageError("consistency needs the shapes: --source M1 --target M2");
    }
    if (o.stride < 1) throw UsageError("--stride must be >= 1");
    if (o.threads < 0) throw UsageError("--threads must be >= 0");
    if (o.distanceLevel < 0) throw UsageError("--distance-level must be >= 1");
    return o;
}

Json
domainJson(const eval::DomainError& e, const eval::VertexError& v, double scale)
{
    return Json{{"omega_l2", e.l2 * scale},
                {"omega_linf", e.linf * scale},
                {"shape_mean", v.mean * scale},
                {"shape_max", v.max * scale}};
}

Json
inverseJson(const eval::ConsistencyReport& r, const eval::DomainError& e,
            const eval::VertexError& v)
{
    return Json{{"world", domainJson(e, v, 1.0)},
                {"relative", domainJson(e, v, 1.0 / r.domainSize)},
                {"omega_points", e.points},
                {"shape_vertices", v.points}};
}

/// phi^{-1} o phi - Id over Omega: no shape part.
Json
roundTripJson(const eval::ConsistencyReport& r)
{
    const eval::DomainError& e = r.inverseRoundTripDomain;
    auto norms = [&](double scale) {
        return Json{{"omega_l2", e.l2 * scale}, {"omega_linf", e.linf * scale}};
    };
    return Json{{"world", norms(1.0)},
                {"relative", norms(1.0 / r.domainSize)},
                {"omega_points", e.points},
                {"failures", r.inverseFailures}};
}

Json
residualJson(const eval::ConsistencyReport& r, const eval::VertexError& v)
{
    return Json{{"world", Json{{"mean", v.mean}, {"max", v.max}}},
                {"relative", Json{{"mean", r.relative(v.mean)}, {"max", r.relative(v.max)}}},
                {"vertices", v.points}};
}

Json
detJson(const eval::JacobianStats& s)
{
    return Json{{"min", s.min},
                {"max", s.max},
                {"simplices", s.simplices},
                {"threshold", eval::DET_LOW_THRESHOLD},
                {"below_threshold", s.belowThreshold},
                {"fraction_below_threshold", s.fractionBelowThreshold()},
                {"non_positive", s.nonPositive},
                {"fraction_non_positive", s.fractionNonPositive()}};
}

void
printJson(std::ostream& out, const ConsistencyCliOptions& o, const eval::ConsistencyReport& r)
{
    Json j;
    j["phi"] = o.phi;
    j["psi"] = o.psi;
    j["source"] = o.source;
    j["target"] = o.target;
    j["dimension"] = r.dim;
    j["domain_size"] = r.domainSize;
    j["sample_spacing"] = r.sampleSpacing;
    j["distance_level"] = r.distanceLevel;
    j["distance_voxel"] = r.distanceVoxel;
    j["psi_phi"] = inverseJson(r, r.psiPhiDomain, r.psiPhiShape);
    j["phi_psi"] = inverseJson(r, r.phiPsiDomain, r.phiPsiShape);
    j["inverse_round_trip"] = roundTripJson(r);
    j["psi_vs_inverse"] = inverseJson(r, r.psiVsInverseDomain, r.psiVsInverseShape);
    j["psi_vs_inverse"]["failures"] = r.psiVsInverseFailures;
    j["residual_phi"] = residualJson(r, r.residualPhi);
    j["residual_psi"] = residualJson(r, r.residualPsi);
    j["det_phi"] = detJson(r.detPhi);
    j["det_psi"] = detJson(r.detPsi);
    out << dumpJson(j);
}

void
printTable(std::ostream& out, const ConsistencyCliOptions& o, const eval::ConsistencyReport& r)
{
    /// Width of the label column.
    constexpr std::size_t LABEL_WIDTH = 39;
    auto row = [&](const std::string& what, double world) {
        out << "  " << what
            << std::string(what.size() < LABEL_WIDTH ? LABEL_WIDTH - what.size() : 1, ' ')
            << fixed("%11.4e", world) << "   " << fixed("%11.4e", r.relative(world)) << "\n";
    };
    auto det = [&](const std::string& name, const eval::JacobianStats& s) {
        out << "  " << name << ": min " << fixed("%.4g", s.min) << ", max " << fixed("%.4g", s.max)
            << ", below " << formatNumber(eval::DET_LOW_THRESHOLD) << ": "
            << fixed("%.3g", 100 * s.fractionBelowThreshold())
            << "%, <= 0: " << fixed("%.3g", 100 * s.fractionNonPositive()) << "% of " << s.simplices
            << " simplices\n";
    };
    out << "phi: " << o.phi << "\npsi: " << o.psi << "\nM1:  " << o.source << "\nM2:  " << o.target
        << "\n";
    out << r.dim << "D, domain size " << formatNumber(r.domainSize)
        << " (world units), Omega sampled every " << fixed("%.4g", r.sampleSpacing) << " ("
        << r.psiPhiDomain.points << " points), distances at level " << r.distanceLevel << "\n\n";
    out << "  " << std::string(LABEL_WIDTH, ' ') << "      world   / domain size\n";
    row("|psi(phi(x)) - x|     Omega  L2 (rms)", r.psiPhiDomain.l2);
    row("                      Omega  Linf", r.psiPhiDomain.linf);
    row("                      M1     mean", r.psiPhiShape.mean);
    row("                      M1     max", r.psiPhiShape.max);
    row("|phi(psi(y)) - y|     Omega  L2 (rms)", r.phiPsiDomain.l2);
    row("                      Omega  Linf", r.phiPsiDomain.linf);
    row("                      M2     mean", r.phiPsiShape.mean);
    row("                      M2     max", r.phiPsiShape.max);
    row("|phi^-1(phi(x)) - x|  Omega  L2 (rms)", r.inverseRoundTripDomain.l2);
    row("                      Omega  Linf", r.inverseRoundTripDomain.linf);
    row("|psi(y) - phi^-1(y)|  Omega  L2 (rms)", r.psiVsInverseDomain.l2);
    row("                      Omega  Linf", r.psiVsInverseDomain.linf);
    row("                      M2     mean", r.psiVsInverseShape.mean);
    row("                      M2     max", r.psiVsInverseShape.max);
    row("|d2(phi(x))| on M1           mean", r.residualPhi.mean);
    row("                             max", r.residualPhi.max);
    row("|d1(psi(y))| on M2           mean", r.residualPsi.mean);
    row("                             max", r.residualPsi.max);
    out << "\n";
    det("det D phi", r.detPhi);
    det("det D psi", r.detPsi);
    out << "  phi^-1 = exact inverse of phi; walks that failed (met det D phi <= 0): "
        << r.inverseFailures << " of " << r.inverseRoundTripDomain.points << " (round trip), "
        << r.psiVsInverseFailures << " of "
        << r.psiVsInverseDomain.points + r.psiVsInverseShape.points << " (psi vs phi^-1)\n";
}

Shape
readShapeInput(const std::string& path, const std::string& gridName, const char* option)
{
    if (!gridName.empty() && isShapeFile(path) && !isLevelSetFile(path)) {
        throw UsageError(std::string(option) + " applies to .vdb shapes, not to '" + path + "'");
    }
    return readShape(path, gridName);
}

} // namespace

int
runConsistencyCommand(int argc, const char* const* argv, int first, std::ostream& out,
                      std::ostream&)
{
    const ConsistencyCliOptions o = parseConsistencyOptions(argc, argv, first);
    openvdb::initialize();
    SignalScope signals;
    std::optional<tbb::global_control> threadLimit;
    if (o.threads > 0) {
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    }
    const DeformationField phi = DeformationField::read(o.phi);
    const DeformationField psi = DeformationField::read(o.psi);
    const Shape m1 = readShapeInput(o.source, o.sourceGrid, "--source-grid");
    const Shape m2 = readShapeInput(o.target, o.targetGrid, "--target-grid");
    checkInterrupted();
    if (m1.dim != m2.dim) {
        OPENVDB_THROW(openvdb::ValueError, "M1 is " + std::to_string(m1.dim) + "D and M2 " +
                                               std::to_string(m2.dim) + "D");
    }
    eval::ConsistencyOptions opts;
    opts.stride = o.stride;
    opts.distanceLevel = o.distanceLevel;
    SignalInterrupter interrupter;
    const eval::ConsistencyReport report =
        m1.dim == 2
            ? eval::measureConsistency<2>(phi, psi, m1.curve, m2.curve, opts, &interrupter)
            : eval::measureConsistency<3>(phi, psi, m1.surface, m2.surface, opts, &interrupter);
    checkInterrupted();
    if (o.json) {
        printJson(out, o, report);
    } else {
        printTable(out, o, report);
    }
    out.flush();
    return EXIT_OK;
}

std::string
consistencyOptionHelp()
{
    return optionHelp(consistencyOptionTable());
}

std::vector<OptionDescription>
consistencyOptionDescriptions()
{
    return describeOptions(consistencyOptionTable());
}

} // namespace cli
} // namespace vdbmatch
