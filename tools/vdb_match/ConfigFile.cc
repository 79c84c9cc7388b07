/// @file ConfigFile.cc
#include "ConfigFile.h"

#include <vdbmatch/Parameters.h>

#include <openvdb/Exceptions.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>

namespace vdbmatch {
namespace cli {

const std::vector<std::pair<const char*, const char*>>&
configKeys()
{
    static const std::vector<std::pair<const char*, const char*>> keys = {
        {"preset", "--preset"},
        {"energy", "--energy"},
        {"cMatch", "--c-match"},
        {"cMem", "--c-mem"},
        {"coarseMembraneFactor", "--coarse-membrane-factor"},
        {"membraneSaturation", "--membrane-saturation"},
        {"membraneSaturationLevels", "--membrane-saturation-levels"},
        {"cBend", "--c-bend"},
        {"cVol", "--c-vol"},
        {"coarseVolumeFactor", "--coarse-volume-factor"},
        {"coarseSigmaFactor", "--coarse-sigma-factor"},
        {"q", "--q"},
        {"theta", "--theta"},
        {"tau", "--tau"},
        {"hessianSmoothing", "--hessian-smoothing"},
        {"noiseSmoothing", "--noise-smoothing"},
        {"latticeNoiseSmoothing", "--lattice-noise-smoothing"},
        {"noiseBending", "--noise-bending"},
        {"minLevel", "--min-level"},
        {"maxLevel", "--max-level"},
        {"margin", "--margin"},
        {"refinementMarginCells", "--refine-margin"},
        {"metricTauFactor", "--metric-tau"},
        {"optimizer", "--optimizer"},
        {"initialStep", "--initial-step"},
        {"trialGrowth", "--trial-growth"},
        {"metricTolerance", "--metric-tolerance"},
        {"maxIterations", "--max-iterations"},
        {"energyTolerance", "--energy-tolerance"},
        {"settleTolerance", "--settle-tolerance"},
        {"toleranceCoarsening", "--tolerance-coarsening"},
        {"iterationCoarsening", "--iteration-coarsening"},
        {"surfaceTolerance", "--surface-tolerance"},
        {"surfaceLevels", "--surface-levels"},
        {"surfaceFromLevel", "--surface-from-level"},
        {"relativeGradientTolerance", "--gradient-tolerance"},
        {"landmarkWeight", "--landmark-weight"},
        {"landmarks", "--landmarks"},
        {"autoLandmarks", "--auto-landmarks"},
        {"autoLandmarkLevels", "--auto-landmark-levels"},
        {"autoLandmarkMinMotion", "--auto-landmark-min-motion"},
        {"autoAnchors", "--auto-anchors"},
        {"landmarkAnchors", "--landmark-anchors"},
        {"secondPath", "--second-path"},
        {"secondPathShare", "--second-path-share"},
        {"secondPathTarget", "--second-path-target"},
        {"anchorWeight", "--anchor-weight"},
        {"anchorCount", "--anchor-count"},
        {"anchorRadius", "--anchor-radius"},
        {"anchorTolerance", "--anchor-tolerance"},
        {"anchorNoiseTolerance", "--anchor-noise-tolerance"},
        {"rigidLimbWeight", "--rigid-limb-weight"},
        {"rigidLimbMinMotion", "--rigid-limb-min-motion"},
        {"rigidLimbAnchorRadius", "--rigid-limb-anchor-radius"},
        {"rigidLimbCount", "--rigid-limb-count"},
        {"rigidLimbReach", "--rigid-limb-reach"},
        {"rigidSegment", "--rigid-segment"},
        {"rigidSegmentMinAngle", "--rigid-segment-min-angle"},
        {"rigidSegmentTipMotion", "--rigid-segment-tip-motion"},
        {"innerDistanceWeight", "--inner-distance-weight"},
        {"innerDistanceTolerance", "--inner-distance-tolerance"},
        {"innerDistanceRatio", "--inner-distance-ratio"},
        {"innerDistanceLevel", "--inner-distance-level"},
        {"innerDistanceLevels", "--inner-distance-levels"},
    };
    return keys;
}

std::vector<ConfigSetting>
parseConfig(const std::string& text, const std::string& path)
{
    using Json = nlohmann::ordered_json;
    const Json doc = Json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (doc.is_discarded() || !doc.is_object()) {
        OPENVDB_THROW(openvdb::ValueError, "--config: '"
                                               << path
                                               << "' is not a JSON object (a report.json or its "
                                                  "\"parameters\")");
    }
    const Json& params = doc.contains("parameters") ? doc["parameters"] : doc;
    if (!params.is_object()) {
        OPENVDB_THROW(openvdb::ValueError,
                      "--config: \"parameters\" in '" << path << "' is not an object");
    }
    std::vector<ConfigSetting> settings;
    for (const auto& [key, value] : params.items()) {
        // Written by match but fixed by the method (tab:parameters): must hold its value.
        if (key == "sigmaFactor") {
            if (!value.is_number() || value.get<double>() != EnergyParameters().sigmaFactor) {
                OPENVDB_THROW(openvdb::ValueError, "--config: sigmaFactor is fixed at "
                                                       << EnergyParameters().sigmaFactor
                                                       << " (sigma = 2h)");
            }
            continue;
        }
        const char* option = nullptr;
        for (const auto& [name, opt] : configKeys())
            if (key == name) option = opt;
        if (!option) {
            std::string known;
            for (const auto& kv : configKeys())
                known += std::string(known.empty() ? "" : ", ") + kv.first;
            OPENVDB_THROW(openvdb::ValueError, "--config: unknown key '" << key << "' in '" << path
                                                                         << "' (known: " << known
                                                                         << ")");
        }
        // "landmarks": the two files of --landmarks.
        if (key == "landmarks") {
            if (!value.is_array() || value.size() != 2 || !value[0].is_string() ||
                !value[1].is_string()) {
                OPENVDB_THROW(openvdb::ValueError,
                              "--config: 'landmarks' must be an array of two file names");
            }
            for (const auto& file : value)
                settings.push_back({key, option, file.get<std::string>()});
            continue;
        }
        if (!value.is_number() && !value.is_string()) {
            OPENVDB_THROW(openvdb::ValueError,
                          "--config: '" << key << "' must be a number or a string");
        }
        settings.push_back(
            {key, option, value.is_string() ? value.get<std::string>() : value.dump()});
    }
    // A report.json of a version before the surface test (its parameters have the stopping rule
    // but no surfaceTolerance) ran without it: reproduce that run, not today's default.
    if (doc.contains("parameters") && params.contains("energyTolerance") &&
        !params.contains("surfaceTolerance")) {
        settings.push_back({"surfaceTolerance", "--surface-tolerance", "0"});
    }
    // Likewise a report.json of a version before the coarse membrane factor (energy
    // coefficients but no coarseMembraneFactor) used one c_mem at every level.
    if (doc.contains("parameters") && params.contains("cMem") &&
        !params.contains("coarseMembraneFactor")) {
        settings.push_back({"coarseMembraneFactor", "--coarse-membrane-factor", "1"});
    }
    // ... and one before the surface test from a fixed level (no surfaceFromLevel) applied it
    // at the last surfaceLevels levels only, if at all.
    if (doc.contains("parameters") && params.contains("energyTolerance") &&
        !params.contains("surfaceFromLevel")) {
        settings.push_back({"surfaceFromLevel", "--surface-from-level", "0"});
    }
    // ... and one before the membrane saturation (energy coefficients but no
    // membraneSaturation) used the paper's membrane density at every level.
    if (doc.contains("parameters") && params.contains("cMem") &&
        !params.contains("membraneSaturation")) {
        settings.push_back({"membraneSaturation", "--membrane-saturation", "0"});
    }
    // ... and one before automatic landmarks (no autoLandmarks) had none.
    if (doc.contains("parameters") && params.contains("landmarkWeight") &&
        !params.contains("autoLandmarks")) {
        settings.push_back({"autoLandmarks", "--auto-landmarks", "off"});
    }
    // ... and one before automatic anchors (no autoAnchors) had none.
    if (doc.contains("parameters") && params.contains("landmarkWeight") &&
        !params.contains("autoAnchors")) {
        settings.push_back({"autoAnchors", "--auto-anchors", "off"});
    }
    // ... and one before the anchors beside given landmarks (no landmarkAnchors) had none with
    // --landmarks.
    if (doc.contains("parameters") && params.contains("landmarkWeight") &&
        !params.contains("landmarkAnchors")) {
        settings.push_back({"landmarkAnchors", "--landmark-anchors", "off"});
    }
    // ... and one before the inner-distance term (no innerDistanceWeight) had none.
    if (doc.contains("parameters") && params.contains("landmarkWeight") &&
        !params.contains("innerDistanceWeight")) {
        settings.push_back({"innerDistanceWeight", "--inner-distance-weight", "0"});
    }
    // ... and one before the rigid limbs (no rigidLimbWeight) had none.
    if (doc.contains("parameters") && params.contains("landmarkWeight") &&
        !params.contains("rigidLimbWeight")) {
        settings.push_back({"rigidLimbWeight", "--rigid-limb-weight", "0"});
    }
    // ... and one before the rigid segments (no rigidSegment) had none.
    if (doc.contains("parameters") && params.contains("rigidLimbWeight") &&
        !params.contains("rigidSegment")) {
        settings.push_back({"rigidSegment", "--rigid-segment", "off"});
    }
    // ... and one from before innerDistanceRatio kept every vertex of M1 in it.
    if (doc.contains("parameters") && params.contains("innerDistanceWeight") &&
        !params.contains("innerDistanceRatio")) {
        settings.push_back({"innerDistanceRatio", "--inner-distance-ratio", "1"});
    }
    // ... and one before the second path (no secondPath) ran one path.
    if (doc.contains("parameters") && params.contains("landmarkWeight") &&
        !params.contains("secondPath")) {
        settings.push_back({"secondPath", "--second-path", "off"});
    }
    // ... and one before the noise-adaptive Hessian smoothing (no noiseSmoothing) had none.
    if (doc.contains("parameters") && params.contains("hessianSmoothing") &&
        !params.contains("noiseSmoothing")) {
        settings.push_back({"noiseSmoothing", "--noise-smoothing", "0"});
    }
    // ... and one before the lattice reading of the noise (no latticeNoiseSmoothing) had the
    // vertex reading alone.
    if (doc.contains("parameters") && params.contains("hessianSmoothing") &&
        !params.contains("latticeNoiseSmoothing")) {
        settings.push_back({"latticeNoiseSmoothing", "--lattice-noise-smoothing", "0"});
    }
    // ... and one before the anchors' tolerance followed the noise (no anchorNoiseTolerance)
    // kept the fixed one.
    if (doc.contains("parameters") && params.contains("hessianSmoothing") &&
        !params.contains("anchorNoiseTolerance")) {
        settings.push_back({"anchorNoiseTolerance", "--anchor-noise-tolerance", "0"});
    }
    // ... and one before the noise-adaptive bending weight (no noiseBending) kept c_bend.
    if (doc.contains("parameters") && params.contains("hessianSmoothing") &&
        !params.contains("noiseBending")) {
        settings.push_back({"noiseBending", "--noise-bending", "0"});
    }
    return settings;
}

std::vector<ConfigSetting>
readConfig(const std::string& path)
{
    std::error_code ec;
    const bool directory = std::filesystem::is_directory(path, ec);
    std::ifstream in(path, std::ios::binary);
    if (!in || directory) {
        OPENVDB_THROW(openvdb::IoError, "--config: cannot read '" << path << "'");
    }
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec && size > MAX_CONFIG_BYTES) {
        OPENVDB_THROW(openvdb::IoError, "--config: '" << path << "' has " << size
                                                      << " bytes; a parameter file has a few KB "
                                                         "(at most "
                                                      << MAX_CONFIG_BYTES << ")");
    }
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return parseConfig(text, path);
}

} // namespace cli
} // namespace vdbmatch
