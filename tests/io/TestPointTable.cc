/// @file TestPointTable.cc
/// @brief Tests of PointTable: CSV and XYZ tables round-trip byte for byte, moved coordinates
/// change only the x, y, z fields, 2D tables, error types and messages, atomic writes.

#include "support/TestSurfaces.h"

#include <vdbmatch/io/PointTable.h>

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

using namespace vdbmatch;
using namespace vdbmatch::test;
namespace fs = std::filesystem;
using openvdb::Vec3d;

namespace {

void
writeText(const std::string& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
}

std::string
readText(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string
shortest(double v)
{
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    return std::string(buf, r.ptr);
}

Vec3d
affine(const Vec3d& p)
{
    return Vec3d(1.5 * p[0] + 0.25 * p[1] + 0.1, -0.5 * p[1] + 2.0 * p[2] - 0.3,
                 0.75 * p[2] + 0.2 * p[0] + 0.7);
}

/// Expects PointTable::read to throw E with a message naming the file and containing @a text.
template <typename E>
void
expectReadError(const std::string& path, int dimension, const std::string& text)
{
    try {
        PointTable::read(path, dimension);
        ADD_FAILURE() << "no exception for " << path;
    } catch (const E& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(text), std::string::npos) << what;
        EXPECT_NE(what.find(fs::path(path).filename().string()), std::string::npos) << what;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type for " << path << ": " << e.what();
    }
}

/// A CSV table in the style of antsApplyTransformsToPoints, with string and quoted columns.
std::string
csv(const std::vector<std::string>& x, const std::vector<std::string>& y,
    const std::vector<std::string>& z)
{
    return "id,X, y ,z,t,label,\"note, quoted\"\r\n"
           "1," +
           x[0] + "," + y[0] + "," + z[0] +
           ",0,left,\"a,b\"\r\n"
           "# a comment, kept\r\n"
           "\r\n"
           "2, " +
           x[1] + " ," + y[1] + ",\"" + z[1] +
           "\",1.5,\"right \"\"eye\"\"\",\r\n"
           "3," +
           x[2] + "," + y[2] + "," + z[2] + ",2,,plain\r\n";
}

class PointTableTest : public ::testing::Test
{
protected:
    ScratchDir mDir;
};

} // namespace

TEST_F(PointTableTest, CsvRoundTripAndMove)
{
    const std::vector<std::string> x{"0.500", "-1e-3", "10"}, y{"1.25", "2", "+3.0"},
        z{"-3", "0.1", "7.000000"};
    const std::string in = mDir.file("points.CSV"), out = mDir.file("out.csv");
    const std::string text = csv(x, y, z);
    writeText(in, text);
    PointTable table = PointTable::read(in, 3);
    ASSERT_EQ(table.size(), 3u);
    EXPECT_EQ(table.positions()[0], Vec3d(0.5, 1.25, -3));
    EXPECT_EQ(table.positions()[1], Vec3d(-1e-3, 2, 0.1));
    EXPECT_EQ(table.positions()[2], Vec3d(10, 3, 7));
    ASSERT_EQ(table.columns().size(), 7u);
    EXPECT_EQ(table.columns()[6], "note, quoted");
    table.write(out);
    EXPECT_EQ(readText(out), text);

    std::vector<std::string> nx, ny, nz;
    for (Vec3d& p : table.positions()) {
        p = affine(p);
        nx.push_back(shortest(p[0]));
        ny.push_back(shortest(p[1]));
        nz.push_back(shortest(p[2]));
    }
    table.positions()[2][1] = 3.0; // unchanged: keeps its text "+3.0"
    ny[2] = "+3.0";
    table.write(out);
    EXPECT_EQ(readText(out), csv(nx, ny, nz));
    const PointTable back = PointTable::read(out, 3);
    for (std::size_t i = 0; i < 3; ++i)
        EXPECT_EQ(back.positions()[i], table.positions()[i]);
}

TEST_F(PointTableTest, XyzWithHashHeaderAndTabs)
{
    const std::string text = "# X\tY\tZ\tlabel\n0.1\t0.2\t0.3\tnose\n\n# comment\n"
                             "1 2 3 chin\n  -4   5.5 6e1  ear\n";
    for (const char* name : {"p.xyz", "p.txt"}) {
        const std::string in = mDir.file(name), out = mDir.file(std::string("out_") + name);
        writeText(in, text);
        PointTable table = PointTable::read(in, 3);
        ASSERT_EQ(table.size(), 3u);
        EXPECT_EQ(table.positions()[2], Vec3d(-4, 5.5, 60));
        table.write(out);
        EXPECT_EQ(readText(out), text);
        table.positions()[0] = Vec3d(0.5, -0.25, 1.0 / 3.0);
        table.positions()[2][0] = 8;
        table.write(out);
        EXPECT_EQ(readText(out), "# X\tY\tZ\tlabel\n0.5\t-0.25\t" + shortest(1.0 / 3.0) +
                                     "\tnose\n\n# comment\n1 2 3 chin\n  8   5.5 6e1  ear\n");
    }
}

TEST_F(PointTableTest, TwoDimensional)
{
    const std::string in = mDir.file("p2.csv"), out = mDir.file("out2.csv");
    writeText(in, "y,x,label\n1,2,a\n3,4,b\n");
    expectReadError<openvdb::ValueError>(in, 3, "column 'z' missing");
    PointTable table = PointTable::read(in, 2);
    EXPECT_EQ(table.dimension(), 2);
    ASSERT_EQ(table.size(), 2u);
    EXPECT_EQ(table.positions()[0], Vec3d(2, 1, 0));
    table.positions()[1] = Vec3d(0.5, 0.25, 9);
    table.write(out);
    EXPECT_EQ(readText(out), "y,x,label\n1,2,a\n0.25,0.5,b\n");

    // A z column in 2D is read but written as it was.
    const std::string in3 = mDir.file("p3.csv");
    writeText(in3, "x,y,z\n1,2,3.50\n");
    PointTable withZ = PointTable::read(in3, 2);
    EXPECT_EQ(withZ.positions()[0], Vec3d(1, 2, 3.5));
    withZ.positions()[0] = Vec3d(-1, -2, -3);
    withZ.write(out);
    EXPECT_EQ(readText(out), "x,y,z\n-1,-2,3.50\n");
}

TEST_F(PointTableTest, ErrorsNameTheFileAndLine)
{
    using openvdb::IoError;
    using openvdb::ValueError;
    expectReadError<IoError>(mDir.file("missing.csv"), 3, "does not exist");
    fs::create_directories(mDir.file("dir.csv"));
    expectReadError<IoError>(mDir.file("dir.csv"), 3, "is a directory");
    writeText(mDir.file("p.dat"), "x y z\n");
    expectReadError<ValueError>(mDir.file("p.dat"), 3, "unknown point file extension");
    writeText(mDir.file("ok.csv"), "x,y,z\n");
    expectReadError<ValueError>(mDir.file("ok.csv"), 4, "dimension must be 2 or 3");
    EXPECT_EQ(PointTable::read(mDir.file("ok.csv"), 3).size(), 0u);

    writeText(mDir.file("empty.csv"), "");
    expectReadError<ValueError>(mDir.file("empty.csv"), 3, "missing header");
    writeText(mDir.file("blank.xyz"), "\n  \n");
    expectReadError<ValueError>(mDir.file("blank.xyz"), 3, "missing header");
    writeText(mDir.file("nohead.csv"), "1,2,3\n");
    expectReadError<ValueError>(mDir.file("nohead.csv"), 3, "line 1: column 'x' missing");
    writeText(mDir.file("twice.csv"), "x,y,z,X\n");
    expectReadError<ValueError>(mDir.file("twice.csv"), 3, "column 'x' appears twice");
    writeText(mDir.file("fields.csv"), "x,y,z,label\n1,2,3,a\n4,5,6\n");
    expectReadError<ValueError>(mDir.file("fields.csv"), 3, "line 3: expected 4 fields");
    writeText(mDir.file("quoted.csv"), "x,y,z,label\n1,2,3,\"a,b\n");
    expectReadError<ValueError>(mDir.file("quoted.csv"), 3, "line 2: a quoted field is not");
    writeText(mDir.file("word.xyz"), "x y z\n1 2 3\n1 two 3\n");
    expectReadError<ValueError>(mDir.file("word.xyz"), 3, "line 3: coordinate 'y' is not a");
    writeText(mDir.file("nan.csv"), "x,y,z\n1,2,nan\n");
    expectReadError<ValueError>(mDir.file("nan.csv"), 3, "line 2: coordinate 'z' is not a");
    writeText(mDir.file("inf.csv"), "x,y\n-inf,2\n");
    expectReadError<ValueError>(mDir.file("inf.csv"), 2, "line 2: coordinate 'x' is not a");
}

TEST_F(PointTableTest, WriteFailuresLeaveNoFile)
{
    writeText(mDir.file("p.csv"), "x,y,z\n1,2,3\n");
    PointTable table = PointTable::read(mDir.file("p.csv"), 3);
    EXPECT_THROW(table.write(mDir.file("no/such/dir/out.csv")), openvdb::IoError);
    EXPECT_FALSE(fs::exists(mDir.file("no")));
    table.positions()[0][2] = std::numeric_limits<double>::infinity();
    EXPECT_THROW(table.write(mDir.file("inf.csv")), openvdb::ValueError);
    EXPECT_FALSE(fs::exists(mDir.file("inf.csv")));
    table.positions().clear();
    EXPECT_THROW(table.write(mDir.file("empty.csv")), openvdb::ValueError);
    EXPECT_FALSE(fs::exists(mDir.file("empty.csv")));
}
