/// @file TestLevelSetIO.cc
/// @brief Tests of readLevelSet (grid selection, every rejected kind of input and its exception
/// type and message), checkInputLevelSet, and writeGridsAtomically.

#include <vdbmatch/io/DeformationIO.h>
#include <vdbmatch/io/LevelSetIO.h>
#include <vdbmatch/io/VdbFileCheck.h>

#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <sys/resource.h>
#include <unistd.h>

using namespace vdbmatch;
namespace fs = std::filesystem;

namespace {

constexpr float VOXEL = 0.1f;
constexpr float RADIUS = 1.0f;

/// A scratch directory of its own for each test, removed at the end.
class ScratchDir
{
public:
    ScratchDir()
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        mPath = fs::temp_directory_path() / ("vdbmatch-" + std::string(info->test_suite_name()) +
                                             "-" + info->name() + "-" + std::to_string(::getpid()));
        fs::remove_all(mPath);
        fs::create_directories(mPath);
    }
    ~ScratchDir()
    {
        std::error_code ec;
        fs::remove_all(mPath, ec);
    }
    std::string file(const std::string& name) const { return (mPath / name).string(); }
    const fs::path& path() const { return mPath; }

private:
    fs::path mPath;
};

openvdb::FloatGrid::Ptr
sphere(const std::string& name = "surface", float radius = RADIUS)
{
    auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        radius, openvdb::Vec3f(0.2f, -0.1f, 0.3f), VOXEL);
    grid->setName(name);
    return grid;
}

void
write(const std::string& path, const openvdb::GridPtrVec& grids)
{
    openvdb::io::File file(path);
    file.write(grids);
    file.close();
}

/// Runs f and returns the message of the exception of type E it throws ("" if none).
template <typename E, typename F>
std::string
messageOf(F&& f)
{
    try {
        f();
    } catch (const E& e) {
        return e.what();
    }
    return "";
}

bool
contains(const std::string& s, const std::string& part)
{
    return s.find(part) != std::string::npos;
}

class LevelSetIOTest : public ::testing::Test
{
protected:
    void SetUp() override { openvdb::initialize(); }
    ScratchDir mDir;
};

} // namespace

TEST_F(LevelSetIOTest, ReadsTheOnlyFloatGrid)
{
    const auto original = sphere();
    // A vector grid beside it is not a candidate.
    auto vectors = openvdb::Vec3SGrid::create();
    vectors->setName("velocity");
    write(mDir.file("a.vdb"), {original, vectors});
    const auto grid = readLevelSet(mDir.file("a.vdb"));
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getName(), "surface");
    EXPECT_EQ(grid->activeVoxelCount(), original->activeVoxelCount());
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
}

TEST_F(LevelSetIOTest, ReadsANamedGridAmongSeveral)
{
    write(mDir.file("two.vdb"), {sphere("outer", 1.0f), sphere("inner", 0.5f)});
    const auto inner = readLevelSet(mDir.file("two.vdb"), "inner");
    EXPECT_EQ(inner->getName(), "inner");
    EXPECT_EQ(inner->activeVoxelCount(), sphere("inner", 0.5f)->activeVoxelCount());
}

TEST_F(LevelSetIOTest, ReadsAnUnnamedGrid)
{
    write(mDir.file("unnamed.vdb"), {sphere("")});
    EXPECT_TRUE(readLevelSet(mDir.file("unnamed.vdb")));
}

TEST_F(LevelSetIOTest, AcceptsRotatedAndTranslatedTransforms)
{
    auto grid = sphere();
    openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(VOXEL);
    xform->preRotate(0.4, openvdb::math::Z_AXIS);
    xform->postTranslate(openvdb::Vec3d(1.0, -2.0, 0.5));
    grid->setTransform(xform);
    write(mDir.file("rotated.vdb"), {grid});
    EXPECT_TRUE(readLevelSet(mDir.file("rotated.vdb")));
}

TEST_F(LevelSetIOTest, MissingFileIsAnIoError)
{
    const std::string msg =
        messageOf<openvdb::IoError>([&] { readLevelSet(mDir.file("nothere.vdb")); });
    EXPECT_TRUE(contains(msg, "nothere.vdb")) << msg;
    EXPECT_TRUE(contains(msg, "does not exist")) << msg;
    EXPECT_TRUE(contains(messageOf<openvdb::IoError>([&] { readLevelSet(mDir.path().string()); }),
                         "is a directory"));
}

TEST_F(LevelSetIOTest, NonVdbAndTruncatedFilesAreIoErrors)
{
    {
        std::ofstream text(mDir.file("text.vdb"));
        text << "not a vdb file\n";
    }
    EXPECT_TRUE(contains(messageOf<openvdb::IoError>([&] { readLevelSet(mDir.file("text.vdb")); }),
                         "cannot be read as a VDB file"));

    write(mDir.file("whole.vdb"), {sphere()});
    const auto size = fs::file_size(mDir.file("whole.vdb"));
    for (const double fraction : {0.1, 0.5, 0.9}) {
        fs::copy_file(mDir.file("whole.vdb"), mDir.file("cut.vdb"),
                      fs::copy_options::overwrite_existing);
        fs::resize_file(mDir.file("cut.vdb"), std::uintmax_t(double(size) * fraction));
        EXPECT_THROW(readLevelSet(mDir.file("cut.vdb")), openvdb::IoError) << fraction;
    }
}

TEST_F(LevelSetIOTest, NoFloatGridIsATypeError)
{
    auto vectors = openvdb::Vec3SGrid::create();
    vectors->setName("velocity");
    write(mDir.file("vectors.vdb"), {vectors});
    const std::string msg =
        messageOf<openvdb::TypeError>([&] { readLevelSet(mDir.file("vectors.vdb")); });
    EXPECT_TRUE(contains(msg, "no float grid")) << msg;
    EXPECT_TRUE(contains(msg, "'velocity' (vec3s)")) << msg;
    EXPECT_THROW(readLevelSet(mDir.file("vectors.vdb"), "velocity"), openvdb::TypeError);
}

TEST_F(LevelSetIOTest, SeveralFloatGridsNeedAName)
{
    write(mDir.file("two.vdb"), {sphere("outer", 1.0f), sphere("inner", 0.5f)});
    const std::string msg =
        messageOf<openvdb::ValueError>([&] { readLevelSet(mDir.file("two.vdb")); });
    EXPECT_TRUE(contains(msg, "several float grids")) << msg;
    EXPECT_TRUE(contains(msg, "'outer'")) << msg;
    EXPECT_TRUE(contains(msg, "'inner'")) << msg;

    const std::string missing =
        messageOf<openvdb::ValueError>([&] { readLevelSet(mDir.file("two.vdb"), "middle"); });
    EXPECT_TRUE(contains(missing, "no grid named 'middle'")) << missing;
}

TEST_F(LevelSetIOTest, RejectsAFogVolume)
{
    auto fog = sphere("density");
    fog->setGridClass(openvdb::GRID_FOG_VOLUME);
    write(mDir.file("fog.vdb"), {fog});
    const std::string msg =
        messageOf<openvdb::ValueError>([&] { readLevelSet(mDir.file("fog.vdb")); });
    EXPECT_TRUE(contains(msg, "fog.vdb")) << msg;
    EXPECT_TRUE(contains(msg, "not a level set (grid class 'fog volume')")) << msg;
}

TEST_F(LevelSetIOTest, RejectsNonUniformVoxels)
{
    auto grid = sphere();
    openvdb::math::Transform::Ptr scaled = openvdb::math::Transform::createLinearTransform(VOXEL);
    scaled->postScale(openvdb::Vec3d(1.0, 1.0, 2.0));
    grid->setTransform(scaled);
    const std::string msg =
        messageOf<openvdb::ValueError>([&] { checkInputLevelSet(*grid, "scaled"); });
    EXPECT_TRUE(contains(msg, "non-uniform voxels")) << msg;

    openvdb::math::Transform::Ptr sheared = openvdb::math::Transform::createLinearTransform(VOXEL);
    sheared->preShear(0.5, openvdb::math::X_AXIS, openvdb::math::Y_AXIS);
    grid->setTransform(sheared);
    EXPECT_THROW(checkInputLevelSet(*grid, "sheared"), openvdb::ValueError);
}

TEST_F(LevelSetIOTest, RejectsNonFiniteValues)
{
    for (const float bad :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        auto grid = sphere();
        // An active voxel and, separately, an inactive one inside a leaf.
        auto active = grid->deepCopy();
        active->tree().setValueOn(openvdb::Coord(12, 0, 0), bad);
        const std::string msg =
            messageOf<openvdb::ValueError>([&] { checkInputLevelSet(*active, "nan"); });
        EXPECT_TRUE(contains(msg, "non-finite")) << msg;
        auto inactive = grid->deepCopy();
        inactive->tree().setValueOff(openvdb::Coord(2, -1, 3), bad);
        EXPECT_THROW(checkInputLevelSet(*inactive, "nan"), openvdb::ValueError);
    }
}

TEST_F(LevelSetIOTest, RejectsEmptyGridsAndGridsWithoutZeroCrossing)
{
    auto empty = openvdb::FloatGrid::create(3 * VOXEL);
    empty->setGridClass(openvdb::GRID_LEVEL_SET);
    empty->setTransform(openvdb::math::Transform::createLinearTransform(VOXEL));
    write(mDir.file("empty.vdb"), {empty});
    EXPECT_TRUE(contains(
        messageOf<openvdb::ValueError>([&] { readLevelSet(mDir.file("empty.vdb")); }), "empty"));

    auto positive = sphere();
    for (auto it = positive->tree().beginValueOn(); it; ++it)
        it.setValue(std::abs(*it) + VOXEL);
    EXPECT_TRUE(
        contains(messageOf<openvdb::ValueError>([&] { checkInputLevelSet(*positive, "pos"); }),
                 "no zero crossing"));
}

TEST_F(LevelSetIOTest, RejectsOpenSurfacesAndFlippedSigns)
{
    // A sphere clipped by the plane x = 0: the zero crossing reaches the edge of the band.
    auto clipped = sphere();
    for (auto it = clipped->tree().beginValueOn(); it; ++it) {
        if (it.getCoord()[0] > 2) it.setValueOff();
    }
    const std::string msg =
        messageOf<openvdb::ValueError>([&] { checkInputLevelSet(*clipped, "clipped"); });
    EXPECT_TRUE(contains(msg, "open or clipped")) << msg;

    auto flipped = sphere();
    for (auto it = flipped->tree().beginValueOn(); it; ++it)
        it.setValue(-*it);
    EXPECT_THROW(checkInputLevelSet(*flipped, "flipped"), openvdb::ValueError);
}

TEST_F(LevelSetIOTest, AcceptsAThinBand)
{
    // A band of 1.5 voxels on each side (the outer layer at >= 0.5 voxel) is still closed.
    auto thin = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        RADIUS, openvdb::Vec3f(0.0f), VOXEL, /*halfWidth=*/1.5f);
    EXPECT_NO_THROW(checkInputLevelSet(*thin, "thin"));
}

TEST_F(LevelSetIOTest, WritesAtomically)
{
    const std::string path = mDir.file("out.vdb");
    openvdb::MetaMap meta;
    meta.insertMeta("creator", openvdb::StringMetadata("vdbmatch test"));
    writeGridsAtomically(path, {sphere("first")}, meta);
    EXPECT_EQ(readLevelSet(path)->getName(), "first");
    // Overwrite, and check that only the output is left in the directory.
    writeGridsAtomically(path, {sphere("second")}, meta);
    EXPECT_EQ(readLevelSet(path)->getName(), "second");
    int files = 0;
    for (const auto& entry : fs::directory_iterator(mDir.path())) {
        ++files;
        EXPECT_EQ(entry.path().filename(), "out.vdb");
    }
    EXPECT_EQ(files, 1);
    openvdb::io::File file(path);
    file.open();
    EXPECT_EQ(file.getMetadata()->metaValue<std::string>("creator"), "vdbmatch test");
}

TEST_F(LevelSetIOTest, FailedWriteLeavesNothing)
{
    const std::string path = mDir.file("missing-dir/out.vdb");
    EXPECT_THROW(writeGridsAtomically(path, {sphere()}, openvdb::MetaMap()), openvdb::IoError);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::is_empty(mDir.path()));
}

/// Peak resident memory of this process so far, in MB.
double
peakRssMb()
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0; // kilobytes on Linux
}

// Issue 10: a .vdb truncated to 300 bytes made `match` grow to 5.1 GB (OpenVDB allocates from
// lengths it reads; past the end of the file they are uninitialised). checkVdbFileStructure
// now rejects it before OpenVDB reads anything, in readLevelSet and in readDeformation.
TEST_F(LevelSetIOTest, TruncatedFilesFailBeforeAllocating)
{
    write(mDir.file("whole.vdb"), {sphere()});
    const auto size = fs::file_size(mDir.file("whole.vdb"));
    const double rssBefore = peakRssMb();
    for (const std::uintmax_t cut :
         {std::uintmax_t(0), std::uintmax_t(7), std::uintmax_t(8), std::uintmax_t(12),
          std::uintmax_t(57), std::uintmax_t(100), std::uintmax_t(200), std::uintmax_t(300),
          std::uintmax_t(1000), size / 2, size - 1}) {
        fs::copy_file(mDir.file("whole.vdb"), mDir.file("cut.vdb"),
                      fs::copy_options::overwrite_existing);
        fs::resize_file(mDir.file("cut.vdb"), cut);
        const std::string msg =
            messageOf<openvdb::IoError>([&] { readLevelSet(mDir.file("cut.vdb")); });
        EXPECT_TRUE(contains(msg, "cut.vdb")) << cut << ": " << msg;
        EXPECT_TRUE(contains(msg, "truncated") || contains(msg, "cannot be read as a VDB file"))
            << cut << ": " << msg;
        EXPECT_FALSE(
            messageOf<openvdb::IoError>([&] { readDeformation(mDir.file("cut.vdb")); }).empty())
            << cut;
    }
    EXPECT_TRUE(contains(messageOf<openvdb::IoError>([&] {
                             fs::resize_file(mDir.file("cut.vdb"), 300);
                             readLevelSet(mDir.file("cut.vdb"));
                         }),
                         "is truncated or corrupt: grid 0 spans bytes"));
    EXPECT_LT(peakRssMb() - rssBefore, 200.0);
}

// Inputs found or suggested by fuzzing (fuzz/FuzzLevelSetIO.cc, docs/fuzzing.md): each is an
// IoError naming the problem, for both readers, without a huge allocation or a hang.
TEST_F(LevelSetIOTest, FuzzedFilesAreIoErrors)
{
    const std::pair<const char*, const char*> cases[] = {
        // Found by the fuzzer: format version 0 (pre-2013 layout), huge metadata lengths.
        {"vdb_version0_metadata_oom.vdb", "file format version 0 is not supported"},
        {"vdb_version0_timeout.vdb", "file format version 0 is not supported"},
        // Found by the fuzzer: a root tile count of 3.9e9 (a 10 s+ loop in RootNode).
        {"vdb_root_tiles_timeout.vdb", "root tiles"},
        // Found by the fuzzer (second run): a fixed-size metadata value whose stored byte count
        // differs from its size; OpenVDB then read a 1.7 GB name length (9.4 GB resident).
        {"vdb_metadata_size_mismatch_oom.vdb", "value of"},
        // Found by the fuzzer (12-minute run of 2026-11-25): a "__delayedload" value whose own
        // leaf count or blosc block sizes (1.6e9 to 4.3e9) disagree with its 21 stored bytes;
        // io::DelayedLoadMetadata::readValue allocated 1.9 to 4.3 GB from them.
        {"vdb_delayedload_oom_265ed0b4.vdb", "delayed-load value"},
        {"vdb_delayedload_oom_4cc03602.vdb", "delayed-load value"},
        {"vdb_delayedload_oom_603b87aa.vdb", "delayed-load value"},
        {"vdb_delayedload_oom_68bb8da5.vdb", "delayed-load value"},
        {"vdb_delayedload_oom_72e9a3cf.vdb", "delayed-load value"},
        // Crafted from a valid file: one field changed each.
        {"vdb_root_children_4e9.vdb", "4294967295 children"},
        {"vdb_root_tiles_4e9.vdb", "4294967295 root tiles"},
        {"vdb_metadata_name_4gb.vdb", "the grid metadata needs 4294967280 bytes"},
        {"vdb_grid_count_2e9.vdb", "claims 2147483647 grids"},
        {"vdb_grid_end_past_eof.vdb", "grid 0 spans bytes"},
    };
    const double rssBefore = peakRssMb();
    for (const auto& [name, expected] : cases) {
        const std::string path = std::string(VDBMATCH_FUZZ_DATA_DIR) + "/" + name;
        ASSERT_TRUE(fs::exists(path)) << path;
        const std::string msg = messageOf<openvdb::IoError>([&] { readLevelSet(path); });
        EXPECT_TRUE(contains(msg, expected)) << name << ": " << msg;
        const std::string msg2 = messageOf<openvdb::IoError>([&] { readDeformation(path); });
        EXPECT_TRUE(contains(msg2, expected)) << name << ": " << msg2;
    }
    EXPECT_LT(peakRssMb() - rssBefore, 200.0);
}

// Found by the fuzzer: a blosc block size changed to 0 makes OpenVDB read the following mask
// bytes as a block size of 66 TB, which io::bloscFromStream allocates before reading. The
// structure check walks the nodes: their topology no longer ends at the grid's block position.
TEST_F(LevelSetIOTest, FuzzedHugeCompressedBlockIsAnIoError)
{
    const std::string path = std::string(VDBMATCH_FUZZ_DATA_DIR) + "/vdb_blosc_size_66tb.vdb";
    const std::string msg = messageOf<openvdb::IoError>([&] { readLevelSet(path); });
    EXPECT_TRUE(contains(msg, "has a tree topology ending at byte 9940 where its descriptor "
                              "says 9972"))
        << msg;
}

// checkVdbFileStructure walks the nodes of a grid the way OpenVDB reads them: it must accept
// every compression and half-float setting OpenVDB writes (vdb_match --half writes half
// floats), for level sets and deformation grids.
// Every file OpenVDB writes has a "__delayedload" metadata item per grid; for a grid of fewer
// than 128 leaves its blosc-compressed mask decompresses to 128 padded bytes, not to one byte
// per leaf (the check of fuzzing finding 6 first rejected such files).
TEST_F(LevelSetIOTest, StructureCheckAcceptsSmallGridsDelayedLoadMetadata)
{
    for (const float radius : {2.0f, 6.0f, 40.0f}) {
        auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
            radius, openvdb::Vec3f(0.0f), 1.0f, 3.0f);
        grid->setName("surface");
        const std::string path = mDir.file("small.vdb");
        {
            openvdb::io::File file(path);
            file.write({grid});
            file.close();
        }
        SCOPED_TRACE("radius " + std::to_string(radius) + ", " +
                     std::to_string(grid->tree().leafCount()) + " leaves");
        EXPECT_NO_THROW(checkVdbFileStructure(path, "small.vdb"));
        EXPECT_NO_THROW(readLevelSet(path));
    }
}

TEST_F(LevelSetIOTest, StructureCheckAcceptsEveryCompressionAndHalfFloats)
{
    const uint32_t settings[] = {openvdb::io::COMPRESS_NONE, openvdb::io::COMPRESS_ZIP,
                                 openvdb::io::COMPRESS_ACTIVE_MASK,
                                 openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK,
                                 openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK};
    for (const uint32_t compression : settings) {
        for (const bool asHalf : {false, true}) {
            auto grid = sphere();
            grid->setSaveFloatAsHalf(asHalf);
            auto u = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
            u->setName(DEFORMATION_GRID_NAME);
            u->setSaveFloatAsHalf(asHalf);
            u->tree().setValueOn(openvdb::Coord(0, 0, 0), openvdb::Vec3s(0.1f, 0.2f, 0.3f));
            u->tree().setValueOn(openvdb::Coord(100, 7, -50), openvdb::Vec3s(-0.1f));
            u->tree().addTile(1, openvdb::Coord(4096, 0, 0), openvdb::Vec3s(0.5f), true);
            const std::string path = mDir.file("settings.vdb");
            {
                openvdb::io::File file(path);
                file.setCompression(compression);
                file.write({grid, u});
                file.close();
            }
            SCOPED_TRACE("compression " + std::to_string(compression) + ", half " +
                         std::to_string(asHalf));
            EXPECT_NO_THROW(readLevelSet(path, "surface"));
            openvdb::Vec3SGrid::Ptr back;
            EXPECT_NO_THROW(back = readDeformation(path));
            if (back) {
                EXPECT_EQ(back->activeVoxelCount(), u->activeVoxelCount());
            }
        }
    }
}

namespace {

/// A ball of density around (2, 2, 2), voxel 0.1: 1 inside, 0 outside, 0.5 at radius 1.5.
openvdb::FloatGrid::Ptr
densityBall(openvdb::GridClass gridClass)
{
    openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(0.0f);
    g->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    auto acc = g->getAccessor();
    for (int i = 0; i < 40; ++i) {
        for (int j = 0; j < 40; ++j) {
            for (int k = 0; k < 40; ++k) {
                const double r = (openvdb::Vec3d(i, j, k) * 0.1 - openvdb::Vec3d(2.0)).length();
                const double d = std::clamp(0.5 + (1.5 - r) / 0.4, 0.0, 1.0);
                if (d > 0) acc.setValue(openvdb::Coord(i, j, k), float(d));
            }
        }
    }
    g->setGridClass(gridClass);
    g->setName("density");
    return g;
}

} // namespace

TEST(LevelSetIO, DensityIsRefusedWithWhatToDo)
{
    openvdb::initialize();
    for (openvdb::GridClass c : {openvdb::GRID_FOG_VOLUME, openvdb::GRID_UNKNOWN}) {
        try {
            checkInputLevelSet(*densityBall(c), "grid 'density'");
            FAIL() << "expected an error";
        } catch (const openvdb::ValueError& e) {
            EXPECT_NE(std::string(e.what()).find("is not a level set"), std::string::npos);
            EXPECT_NE(std::string(e.what()).find("--iso-value X"), std::string::npos) << e.what();
        }
    }
    // A float grid with negative values is not taken for a density.
    openvdb::FloatGrid::Ptr sdf =
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1, {}, 0.1f);
    sdf->setGridClass(openvdb::GRID_UNKNOWN);
    try {
        checkInputLevelSet(*sdf, "grid 'sdf'");
        FAIL() << "expected an error";
    } catch (const openvdb::ValueError& e) {
        EXPECT_EQ(std::string(e.what()).find("--iso-value"), std::string::npos) << e.what();
    }
}

TEST(LevelSetIO, DensityAtIsoValueIsTheLevelSetOfItsIsoSurface)
{
    openvdb::initialize();
    const openvdb::FloatGrid::Ptr fog = densityBall(openvdb::GRID_FOG_VOLUME);
    const openvdb::FloatGrid::Ptr ls = levelSetAtIsoValue(*fog, 0.5, "grid 'density'");
    EXPECT_EQ(ls->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_EQ(ls->getName(), "density");
    EXPECT_NO_THROW(checkInputLevelSet(*ls, "converted"));
    auto acc = ls->getConstAccessor();
    openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler>
        sampler(acc, ls->transform());
    // Signed distance to the sphere of radius 1.5: negative inside, |error| below a voxel.
    for (const openvdb::Vec3d& p :
         {openvdb::Vec3d(3.5, 2, 2), openvdb::Vec3d(2, 0.5, 2), openvdb::Vec3d(2, 2, 3.5),
          openvdb::Vec3d(3.2, 2, 2), openvdb::Vec3d(2, 2, 0.3)}) {
        const double expected = (p - openvdb::Vec3d(2.0)).length() - 1.5;
        EXPECT_NEAR(sampler.wsSample(p), expected, 0.1) << p;
    }
    // Another iso value gives another sphere: 0.25 at radius 1.6.
    const openvdb::FloatGrid::Ptr wider = levelSetAtIsoValue(*fog, 0.25, "grid 'density'");
    auto wacc = wider->getConstAccessor();
    openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler>
        widerSampler(wacc, wider->transform());
    EXPECT_NEAR(widerSampler.wsSample(openvdb::Vec3d(3.6, 2, 2)), 0.0, 0.1);

    EXPECT_THROW(levelSetAtIsoValue(*fog, 1.5, "x"), openvdb::ValueError);
    EXPECT_THROW(levelSetAtIsoValue(*fog, std::nan(""), "x"), openvdb::ValueError);
    // Level sets are only checked.
    openvdb::FloatGrid::Ptr sphere =
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1, {}, 0.1f);
    EXPECT_EQ(levelSetAtIsoValue(*sphere, 0.5, "x")->activeVoxelCount(),
              sphere->activeVoxelCount());
}
