/// @file TestImageIO.cc
/// @brief Tests of writeExr / writePng / readImage: EXR round trip through OpenImageIO (channel
///        names, size, values including NaN, string attributes), PNG size and bytes, atomic
///        writes leaving no temporary files, and the exceptions for bad input.
#include <vdbmatch/io/ImageIO.h>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <unistd.h>

using namespace vdbmatch;
namespace fs = std::filesystem;

namespace {

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
    size_t entryCount() const
    {
        return static_cast<size_t>(std::distance(fs::directory_iterator(mPath), {}));
    }

private:
    fs::path mPath;
};

ImageChannels
sampleImage()
{
    ImageChannels image;
    image.width = 7;
    image.height = 5;
    image.names = {"phi1", "phi2", "detA"};
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
            image.pixels.push_back(0.25f * x - 1.0f);
            image.pixels.push_back(-0.5f * y + 1e-3f * x);
            image.pixels.push_back(x == 3 && y == 2 ? std::numeric_limits<float>::quiet_NaN()
                                                    : 1.0f + x * y);
        }
    }
    return image;
}

} // namespace

TEST(ImageIO, ExrRoundTripThroughOiio)
{
    ScratchDir dir;
    const ImageChannels image = sampleImage();
    const std::string path = dir.file("slice.exr");
    writeExr(path, image, {{"vdbmatch:source", "a.vdb"}, {"vdbmatch:axis", "z = 0.5"}});
    EXPECT_EQ(dir.entryCount(), 1u) << "a temporary file was left behind";

    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in) << OIIO::geterror();
    const OIIO::ImageSpec& spec = in->spec();
    EXPECT_EQ(spec.width, image.width);
    EXPECT_EQ(spec.height, image.height);
    ASSERT_EQ(spec.nchannels, 3);
    EXPECT_EQ(spec.format, OIIO::TypeDesc::FLOAT);
    EXPECT_EQ(spec.get_string_attribute("vdbmatch:source"), "a.vdb");
    EXPECT_EQ(spec.get_string_attribute("vdbmatch:axis"), "z = 0.5");
    std::vector<float> pixels(image.pixels.size());
    ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data()));

    // Channels may come back in another order: match them by name.
    std::map<std::string, int> fileChannel;
    for (int c = 0; c < spec.nchannels; ++c)
        fileChannel[spec.channelnames[c]] = c;
    for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(fileChannel.count(image.names[c]), 1u) << image.names[c];
        const int fc = fileChannel[image.names[c]];
        for (int y = 0; y < image.height; ++y) {
            for (int x = 0; x < image.width; ++x) {
                const float expected = image.at(x, y, c);
                const float got = pixels[(size_t(y) * image.width + x) * 3 + fc];
                if (std::isnan(expected)) {
                    EXPECT_TRUE(std::isnan(got));
                } else {
                    EXPECT_EQ(got, expected) << image.names[c] << " at " << x << ", " << y;
                }
            }
        }
    }

    ImageAttributes attributes;
    const ImageChannels back = readImage(path, &attributes);
    EXPECT_EQ(back.width, image.width);
    EXPECT_EQ(back.height, image.height);
    const int detA = back.channelIndex("detA");
    ASSERT_GE(detA, 0);
    EXPECT_EQ(back.at(6, 4, detA), 25.0f);
    bool found = false;
    for (const auto& [name, value] : attributes)
        found |= name == "vdbmatch:source" && value == "a.vdb";
    EXPECT_TRUE(found);
}

TEST(ImageIO, ExrOverwritesAtomically)
{
    ScratchDir dir;
    const std::string path = dir.file("slice.exr");
    ImageChannels image = sampleImage();
    writeExr(path, image);
    image.pixels[0] = 42.0f;
    writeExr(path, image);
    EXPECT_EQ(dir.entryCount(), 1u);
    EXPECT_EQ(readImage(path).at(0, 0, readImage(path).channelIndex("phi1")), 42.0f);
}

TEST(ImageIO, ExrRejectsBadInput)
{
    ScratchDir dir;
    ImageChannels image = sampleImage();
    image.pixels.pop_back();
    EXPECT_THROW(writeExr(dir.file("a.exr"), image), openvdb::ValueError);
    image = sampleImage();
    image.names[1] = "phi1";
    EXPECT_THROW(writeExr(dir.file("a.exr"), image), openvdb::ValueError);
    image = sampleImage();
    EXPECT_THROW(writeExr(dir.file("a.exr"), image, {{"channels", "x"}}), openvdb::ValueError);
    image.width = 0;
    EXPECT_THROW(writeExr(dir.file("a.exr"), image), openvdb::ValueError);
    EXPECT_EQ(dir.entryCount(), 0u);
    try {
        writeExr(dir.file("missing/dir/a.exr"), sampleImage());
        FAIL() << "expected IoError";
    } catch (const openvdb::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("writeExr"), std::string::npos) << e.what();
    }
    EXPECT_THROW(readImage(dir.file("none.exr")), openvdb::IoError);
}

TEST(ImageIO, PngRoundTrip)
{
    ScratchDir dir;
    constexpr int W = 40, H = 24;
    std::vector<std::uint8_t> rgb;
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            rgb.push_back(static_cast<std::uint8_t>(6 * x));
            rgb.push_back(static_cast<std::uint8_t>(10 * y));
            rgb.push_back(static_cast<std::uint8_t>((x + y) % 2 ? 255 : 0));
        }
    }
    const std::string path = dir.file("picture.png");
    writePng(path, W, H, rgb);
    EXPECT_EQ(dir.entryCount(), 1u);
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in) << OIIO::geterror();
    EXPECT_EQ(in->spec().width, W);
    EXPECT_EQ(in->spec().height, H);
    ASSERT_EQ(in->spec().nchannels, 3);
    std::vector<std::uint8_t> back(rgb.size());
    ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, back.data()));
    EXPECT_EQ(back, rgb);

    EXPECT_THROW(writePng(path, W, H + 1, rgb), openvdb::ValueError);
    EXPECT_THROW(writePng(dir.file("no/such/dir.png"), W, H, rgb), openvdb::IoError);
}
