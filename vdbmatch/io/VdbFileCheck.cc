/// @file VdbFileCheck.cc
/// @brief Bounds check of the structure of a .vdb file before OpenVDB reads it.
#include "VdbFileCheck.h"

#include <vdbmatch/io/InputFile.h>

#include <openvdb/io/Compression.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <system_error>
#include <utility>
#include <vector>

namespace vdbmatch {

namespace {

/// Bytes of the UUID, stored as text from file format 218 on (OpenVDB io/Archive.cc).
constexpr std::uint64_t UUID_TEXT_BYTES = 36;
/// Bytes of the UUID before file format 218.
constexpr std::uint64_t UUID_BINARY_BYTES = 16;
/// Bytes of the coordinates of a root tile or child (3 int32, RootNode::readTopology).
constexpr std::uint64_t ROOT_ENTRY_COORD_BYTES = 12;
/// Bytes of the active flag of a root tile (bool, RootNode::readTopology).
constexpr std::uint64_t ROOT_TILE_ACTIVE_BYTES = 1;
/// Smallest metadata item: empty name, empty type name, empty value (3 uint32 lengths).
constexpr std::uint64_t MIN_METADATA_ITEM_BYTES = 12;
/// Smallest grid descriptor: 3 empty strings (uint32 lengths) and 3 int64 offsets.
constexpr std::uint64_t MIN_GRID_DESCRIPTOR_BYTES = 3 * 4 + 3 * 8;
/// Longest grid or map type name accepted (the longest OpenVDB names are ~40 characters).
constexpr std::uint64_t MAX_TYPE_NAME_BYTES = 256;
/// Header of a blosc buffer: version, flags, type size, then uncompressed, block and compressed
/// byte counts (uint32 each, little-endian).
constexpr std::uint64_t BLOSC_HEADER_BYTES = 16;
/// OpenVDB pads shorter buffers to this size before blosc compression (io/StreamCompression).
constexpr std::uint64_t BLOSC_PAD_BYTES = 128;

/// Bytes of a value of a tree's value type, from the grid type name ("Tree_float_5_4_3",
/// optionally with the half-float suffix); 0 for a type this check does not know (bool and
/// mask trees store their leaves differently; point grids have their own codecs).
std::uint64_t
valueBytes(const std::string& gridType)
{
    static const std::pair<const char*, std::uint64_t> table[] = {
        {"Tree_float_", 4},  {"Tree_double_", 8}, {"Tree_int32_", 4}, {"Tree_int64_", 8},
        {"Tree_vec3s_", 12}, {"Tree_vec3d_", 24}, {"Tree_vec3i_", 12}};
    for (const auto& [prefix, bytes] : table) {
        if (gridType.rfind(prefix, 0) == 0) return bytes;
    }
    return 0;
}

/// Bytes of a value as stored in uncompressed node data: half floats for a real type saved as
/// half (io::HalfReader), else the value itself.
std::uint64_t
storedValueBytes(const std::string& gridType, std::uint64_t valueSize)
{
    if (gridType.find("_HalfFloat") == std::string::npos) return valueSize;
    if (gridType.rfind("Tree_float_", 0) == 0 || gridType.rfind("Tree_double_", 0) == 0) return 2;
    if (gridType.rfind("Tree_vec3s_", 0) == 0 || gridType.rfind("Tree_vec3d_", 0) == 0) return 6;
    return valueSize;
}

/// Bytes of the two node masks that start the topology of a child of the root: the first
/// number after the value type in the grid type name is the child's log2 dimension
/// ("Tree_float_5_4_3": 32^3 bits per mask); 0 if the name does not say.
std::uint64_t
rootChildMaskBytes(const std::string& gridType)
{
    const std::size_t valueEnd = gridType.find('_', 5);
    if (valueEnd == std::string::npos || valueEnd + 1 >= gridType.size()) return 0;
    const char c = gridType[valueEnd + 1];
    if (c < '1' || c > '9') return 0;
    const std::uint64_t log2Dim = std::uint64_t(c - '0');
    return 2 * ((std::uint64_t(1) << (3 * log2Dim)) / 8);
}

/// Bytes of the linear maps a transform may hold (openvdb/math/Maps.h read(): Mat4d, or
/// Vec3d fields); 0 for another map type (the frustum, whose size varies).
std::uint64_t
mapBytes(const std::string& mapType)
{
    constexpr std::uint64_t VEC3D = 3 * 8, MAT4D = 16 * 8;
    static const std::pair<const char*, std::uint64_t> table[] = {
        {"AffineMap", MAT4D},
        {"UnitaryMap", MAT4D},
        {"ScaleMap", 5 * VEC3D},
        {"UniformScaleMap", 5 * VEC3D},
        {"TranslationMap", VEC3D},
        {"ScaleTranslateMap", 6 * VEC3D},
        {"UniformScaleTranslateMap", 6 * VEC3D}};
    for (const auto& [name, bytes] : table) {
        if (mapType == name) return bytes;
    }
    return 0;
}

/// Bytes of a metadata value of a fixed-size type (openvdb/Metadata.h, registered types);
/// 0 for strings and other types, whose size the stored byte count gives.
std::uint64_t
fixedMetadataBytes(const std::string& type)
{
    static const std::pair<const char*, std::uint64_t> table[] = {
        {"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},  {"double", 8}, {"vec2i", 8},
        {"vec2s", 8},  {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
        {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
    for (const auto& [name, bytes] : table) {
        if (type == name) return bytes;
    }
    return 0;
}

/// Reads little-endian fields of a file, checking each against the file size.
class BoundedReader
{
public:
    BoundedReader(const std::string& path, std::uint64_t size, std::string where)
        : mIn(path, std::ios::binary), mSize(size), mWhere(std::move(where))
    {
        if (!mIn) OPENVDB_THROW(openvdb::IoError, mWhere + " cannot be opened");
    }

    std::uint64_t position() const { return mPos; }
    std::uint64_t remaining() const { return mSize - mPos; }

    /// Fails unless @a n bytes remain; @a what names the field in the message.
    void require(std::uint64_t n, const char* what) const
    {
        if (n > remaining()) {
            fail(std::string("is truncated or corrupt: ") + what + " needs " + std::to_string(n) +
                 " bytes at offset " + std::to_string(mPos) + ", but the file has " +
                 std::to_string(mSize) + " bytes");
        }
    }

    void bytes(void* out, std::uint64_t n, const char* what)
    {
        require(n, what);
        if (!mIn.read(static_cast<char*>(out), std::streamsize(n))) fail("cannot be read");
        mPos += n;
    }

    template <typename T> T value(const char* what)
    {
        unsigned char b[sizeof(T)];
        bytes(b, sizeof(T), what);
        // VDB files are little-endian (OpenVDB writes host order; every supported host is LE).
        T v;
        std::memcpy(&v, b, sizeof(T));
        return v;
    }

    void skip(std::uint64_t n, const char* what)
    {
        require(n, what);
        seek(mPos + n);
    }

    void seek(std::uint64_t pos)
    {
        if (pos > mSize) fail("is corrupt: offset " + std::to_string(pos) + " is past its end");
        mIn.clear();
        if (!mIn.seekg(std::streamoff(pos))) fail("cannot be read");
        mPos = pos;
    }

    /// A length-prefixed string (openvdb readString), skipped; returns its length.
    std::uint64_t skipString(const char* what)
    {
        const std::uint32_t n = value<std::uint32_t>(what);
        skip(n, what);
        return n;
    }

    /// A length-prefixed string of at most @a maxLength bytes (a type name), read.
    std::string shortString(std::uint64_t maxLength, const char* what)
    {
        const std::uint32_t n = value<std::uint32_t>(what);
        require(n, what);
        if (n > maxLength) {
            fail(std::string("is corrupt: ") + what + " is " + std::to_string(n) + " bytes long");
        }
        std::string s(n, '\0');
        if (n > 0) bytes(s.data(), n, what);
        return s;
    }

    /// A MetaMap (openvdb MetaMap::readMeta): count, then name, type name, sized value.
    void skipMetaMap(const char* what)
    {
        const std::uint32_t count = value<std::uint32_t>(what);
        if (count > remaining() / MIN_METADATA_ITEM_BYTES) {
            fail(std::string("is truncated or corrupt: ") + what + " claims " +
                 std::to_string(count) + " items, more than the " + std::to_string(remaining()) +
                 " bytes left can hold");
        }
        for (std::uint32_t i = 0; i < count; ++i) {
            skipString(what);
            const std::string type = shortString(MAX_TYPE_NAME_BYTES, what);
            // The value: Index32 byte count, then the bytes. OpenVDB reads sizeof(T) for a
            // fixed-size type whatever the count says (TypedMetadata::readValue): a count that
            // differs would make it read the next item from other bytes than this check.
            const std::uint32_t n = value<std::uint32_t>(what);
            const std::uint64_t fixed = fixedMetadataBytes(type);
            if (fixed > 0 && n != fixed) {
                fail(std::string("is corrupt: ") + what + " has a '" + type + "' value of " +
                     std::to_string(n) + " bytes, expected " + std::to_string(fixed));
            }
            if (type == "__delayedload" && n > 0) {
                delayedLoadValue(n, what);
            } else {
                skip(n, what);
            }
        }
    }

    /// The value of a "__delayedload" item (openvdb io::DelayedLoadMetadata::readValue), @a n
    /// bytes: Index32 count, then a mask of count bytes and optionally count 8-byte sizes, each
    /// stored raw or as one blosc buffer (Index32 byte count first; 0xffffffff: no sizes).
    /// OpenVDB sizes its arrays from count and from the blosc headers, not from @a n: every
    /// one of them must agree with @a n.
    void delayedLoadValue(std::uint32_t n, const char* what)
    {
        require(n, what);
        const std::uint64_t end = mPos + n;
        auto inside = [&](std::uint64_t bytes) {
            if (bytes > end - mPos) {
                fail(std::string("is corrupt: ") + what +
                     " has a delayed-load value that claims more bytes than its " +
                     std::to_string(n));
            }
        };
        inside(2 * sizeof(std::uint32_t));
        const std::uint32_t count = value<std::uint32_t>(what);
        // One mask byte per leaf node, and a leaf takes more than a byte of the file.
        if (count > mSize) {
            fail(std::string("is corrupt: ") + what + " has a delayed-load value for " +
                 std::to_string(count) + " leaf nodes in a file of " + std::to_string(mSize) +
                 " bytes");
        }
        auto array = [&](std::uint32_t stored, std::uint64_t arrayBytes) {
            if (stored == 0) {
                inside(arrayBytes);
                skip(arrayBytes, what);
                return;
            }
            // A blosc buffer: its header (16 bytes) gives the uncompressed and compressed sizes,
            // which blosc trusts.
            inside(stored);
            if (stored < BLOSC_HEADER_BYTES) fail(std::string("is corrupt: ") + what);
            unsigned char header[BLOSC_HEADER_BYTES];
            bytes(header, BLOSC_HEADER_BYTES, what);
            std::uint32_t uncompressed, compressed;
            std::memcpy(&uncompressed, header + 4, 4);
            std::memcpy(&compressed, header + 12, 4);
            // OpenVDB pads buffers shorter than BLOSC_PAD_BYTES before compressing them
            // (compression::bloscCompress), so a short array decompresses to 128 bytes.
            const std::uint64_t padded = std::max<std::uint64_t>(arrayBytes, BLOSC_PAD_BYTES);
            if (uncompressed < arrayBytes || uncompressed > padded || compressed != stored) {
                fail(std::string("is corrupt: ") + what +
                     " has a delayed-load value whose compressed block sizes disagree (" +
                     std::to_string(uncompressed) + " for " + std::to_string(arrayBytes) +
                     " bytes, " + std::to_string(compressed) + " stored in " +
                     std::to_string(stored) + ")");
            }
            skip(stored - BLOSC_HEADER_BYTES, what);
        };
        array(value<std::uint32_t>(what), count);
        inside(sizeof(std::uint32_t));
        const std::uint32_t sizes = value<std::uint32_t>(what);
        if (sizes != std::numeric_limits<std::uint32_t>::max())
            array(sizes, std::uint64_t(count) * sizeof(std::uint64_t));
        seek(end);
    }

    [[noreturn]] void fail(const std::string& problem) const
    {
        OPENVDB_THROW(openvdb::IoError, mWhere + " " + problem);
    }

private:
    std::ifstream mIn;
    std::uint64_t mSize = 0, mPos = 0;
    std::string mWhere;
};

/// Walks the topology and the leaf buffers of a standard tree (root, internal nodes of log2
/// dimensions 5 and 4, leaves of 3: the "_5_4_3" trees) the way OpenVDB reads them
/// (InternalNode::readTopology, LeafNode::readTopology/readBuffers, io::readCompressedValues)
/// and checks each compressed block size (io::bloscFromStream and unzipFromStream allocate it
/// before reading) against the end of its section. Nothing is allocated from file values.
class TreeWalker
{
public:
    TreeWalker(BoundedReader& in, std::uint32_t compression, std::uint64_t valueSize,
               std::uint64_t storedValueSize, int grid)
        : mIn(in), mCompression(compression), mValueSize(valueSize),
          mStoredValueSize(storedValueSize), mGrid(grid)
    {
    }

    /// The root's children (each: coordinates, then an internal node of log2 dimension 5),
    /// which end at @a topologyEnd (the grid's block position); then the buffers of the leaves
    /// found, which end at @a endPos.
    void walk(std::uint64_t children, std::uint64_t topologyEnd, std::uint64_t endPos)
    {
        mEnd = topologyEnd;
        for (std::uint64_t c = 0; c < children; ++c) {
            skip(ROOT_ENTRY_COORD_BYTES);
            internalNode(UPPER_LOG2DIM);
        }
        // The sections must end where the grid descriptor says: anything else means the
        // nodes are not what their masks and sizes claim, and OpenVDB would read values or
        // block sizes from the wrong bytes.
        if (mIn.position() != topologyEnd) {
            fail("has a tree topology ending at byte " + std::to_string(mIn.position()) +
                 " where its descriptor says " + std::to_string(topologyEnd));
        }
        mEnd = endPos;
        for (std::uint64_t l = 0; l < mLeaves; ++l) {
            std::uint64_t mask[LEAF_MASK_WORDS];
            read(mask, sizeof(mask));
            compressedValues(LEAF_VALUES, popcount(mask, LEAF_MASK_WORDS), LEAF_LOG2DIM);
        }
        if (mIn.position() != endPos) {
            fail("has leaf data ending at byte " + std::to_string(mIn.position()) +
                 " where its descriptor says " + std::to_string(endPos));
        }
    }

private:
    static constexpr int UPPER_LOG2DIM = 5, LOWER_LOG2DIM = 4, LEAF_LOG2DIM = 3;
    static constexpr std::uint64_t LEAF_VALUES = 512, LEAF_MASK_WORDS = LEAF_VALUES / 64;
    /// readCompressedValues metadata (io/Compression.h): which inactive values and selection
    /// mask precede the values.
    enum : std::int8_t {
        NO_MASK_AND_ONE_INACTIVE_VAL = 2,
        MASK_AND_NO_INACTIVE_VALS = 3,
        MASK_AND_ONE_INACTIVE_VAL = 4,
        MASK_AND_TWO_INACTIVE_VALS = 5,
        NO_MASK_AND_ALL_VALS = 6
    };

    static std::uint64_t popcount(const std::uint64_t* words, std::size_t n)
    {
        std::uint64_t count = 0;
        for (std::size_t i = 0; i < n; ++i)
            count += std::uint64_t(__builtin_popcountll(words[i]));
        return count;
    }

    void fail(const std::string& problem) const
    {
        mIn.fail("is corrupt: grid " + std::to_string(mGrid) + " " + problem);
    }

    void skip(std::uint64_t n)
    {
        if (n > mEnd - std::min(mEnd, mIn.position())) fail("runs past the end of its section");
        mIn.skip(n, "a tree node");
    }

    void read(void* out, std::uint64_t n)
    {
        if (n > mEnd - std::min(mEnd, mIn.position())) fail("runs past the end of its section");
        mIn.bytes(out, n, "a tree node");
    }

    /// An internal node's topology: child mask, value mask, its tile values, its children.
    void internalNode(int log2Dim)
    {
        const std::size_t words = (std::size_t(1) << (3 * log2Dim)) / 64;
        std::vector<std::uint64_t> childMask(words), valueMask(words);
        read(childMask.data(), words * 8);
        read(valueMask.data(), words * 8);
        compressedValues(std::uint64_t(words) * 64, popcount(valueMask.data(), words), log2Dim);
        const std::uint64_t children = popcount(childMask.data(), words);
        for (std::uint64_t c = 0; c < children; ++c) {
            if (log2Dim == UPPER_LOG2DIM) {
                internalNode(LOWER_LOG2DIM);
            } else {
                skip(LEAF_MASK_WORDS * 8); // a leaf's topology: its value mask
                ++mLeaves;
            }
        }
    }

    /// io::readCompressedValues of @a count values of which @a active are on.
    void compressedValues(std::uint64_t count, std::uint64_t active, int log2Dim)
    {
        std::int8_t metadata = NO_MASK_AND_ALL_VALS;
        read(&metadata, 1);
        if (metadata == NO_MASK_AND_ONE_INACTIVE_VAL || metadata == MASK_AND_ONE_INACTIVE_VAL ||
            metadata == MASK_AND_TWO_INACTIVE_VALS) {
            skip(mValueSize * (metadata == MASK_AND_TWO_INACTIVE_VALS ? 2 : 1));
        }
        if (metadata == MASK_AND_NO_INACTIVE_VALS || metadata == MASK_AND_ONE_INACTIVE_VAL ||
            metadata == MASK_AND_TWO_INACTIVE_VALS) {
            skip((std::uint64_t(1) << (3 * log2Dim)) / 8); // the selection mask
        }
        const bool maskCompressed = (mCompression & openvdb::io::COMPRESS_ACTIVE_MASK) != 0;
        const std::uint64_t stored =
            maskCompressed && metadata != NO_MASK_AND_ALL_VALS ? active : count;
        // Half floats are read by io::HalfReader, which reads nothing at all for no values.
        const bool halfReal = mStoredValueSize != mValueSize;
        if (halfReal && stored == 0) return;
        if (mCompression & (openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ZIP)) {
            // A negative size stores the bytes uncompressed.
            std::int64_t n = 0;
            read(&n, sizeof(n));
            if (n == std::numeric_limits<std::int64_t>::min()) fail("has an invalid block size");
            const std::uint64_t bytes = std::uint64_t(n < 0 ? -n : n);
            if (bytes > mEnd - std::min(mEnd, mIn.position())) {
                fail("has a compressed block of " + std::to_string(bytes) +
                     " bytes, more than the rest of its section");
            }
            skip(bytes);
        } else {
            skip(stored * mStoredValueSize);
        }
    }

    BoundedReader& mIn;
    std::uint32_t mCompression;
    std::uint64_t mValueSize, mStoredValueSize;
    int mGrid;
    std::uint64_t mEnd = 0, mLeaves = 0;
};

} // namespace

void
checkVdbFileStructure(const std::string& path, const std::string& where)
{
    checkInputFile(path, where);
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) OPENVDB_THROW(openvdb::IoError, where + " cannot be read (" + ec.message() + ")");

    BoundedReader in(path, std::uint64_t(size), where);
    if (size < sizeof(std::int64_t) + sizeof(std::uint32_t)) {
        in.fail("cannot be read as a VDB file (" + std::to_string(size) + " bytes)");
    }
    const std::int64_t magic = in.value<std::int64_t>("the magic number");
    if (magic != std::int64_t(openvdb::OPENVDB_MAGIC)) {
        in.fail("cannot be read as a VDB file (no VDB magic number)");
    }
    const std::uint32_t version = in.value<std::uint32_t>("the file format version");
    // Older formats store the root node as a dense table sized from the file (RootNode.h);
    // OpenVDB has written format 213 and later since 2013.
    if (version < openvdb::OPENVDB_FILE_VERSION_ROOTNODE_MAP) {
        in.fail("cannot be read as a VDB file: file format version " + std::to_string(version) +
                " is not supported (expected " +
                std::to_string(openvdb::OPENVDB_FILE_VERSION_ROOTNODE_MAP) + " to " +
                std::to_string(openvdb::OPENVDB_FILE_VERSION) + ")");
    }
    in.skip(8, "the library version");
    const bool hasGridOffsets = in.value<char>("the grid offsets flag") != 0;
    if (version >= openvdb::OPENVDB_FILE_VERSION_SELECTIVE_COMPRESSION &&
        version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) {
        in.skip(1, "the compression flag");
    }
    in.skip(version >= openvdb::OPENVDB_FILE_VERSION_BOOST_UUID ? UUID_TEXT_BYTES
                                                                : UUID_BINARY_BYTES,
            "the UUID");
    if (!hasGridOffsets) {
        in.fail("was written as a stream, without grid offsets; expected a file written by "
                "openvdb::io::File (Houdini, pyopenvdb, vdb_match)");
    }
    in.skipMetaMap("the file metadata");

    const std::int32_t gridCount = in.value<std::int32_t>("the grid count");
    if (gridCount < 0 || std::uint64_t(gridCount) > in.remaining() / MIN_GRID_DESCRIPTOR_BYTES) {
        in.fail("is truncated or corrupt: it claims " + std::to_string(gridCount) +
                " grids, more than the " + std::to_string(in.remaining()) + " bytes left can hold");
    }
    for (std::int32_t g = 0; g < gridCount; ++g) {
        in.skipString("a grid name");
        const std::string gridType = in.shortString(MAX_TYPE_NAME_BYTES, "a grid type name");
        bool isInstance = false;
        if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) {
            isInstance = in.skipString("a grid instance parent name") > 0;
        }
        const std::int64_t gridPos = in.value<std::int64_t>("a grid offset");
        const std::int64_t blockPos = in.value<std::int64_t>("a grid offset");
        const std::int64_t endPos = in.value<std::int64_t>("a grid offset");
        const std::int64_t here = std::int64_t(in.position());
        if (gridPos < here || blockPos < gridPos || endPos < blockPos ||
            std::uint64_t(endPos) > std::uint64_t(size)) {
            in.fail("is truncated or corrupt: grid " + std::to_string(g) + " spans bytes " +
                    std::to_string(gridPos) + " to " + std::to_string(endPos) + " (data from " +
                    std::to_string(blockPos) + "), the file has " + std::to_string(size) +
                    " bytes");
        }
        // What readAllGridMetadata reads of the grid: compression, metadata, transform type;
        // all of it precedes the grid's topology, which precedes blockPos.
        in.seek(std::uint64_t(gridPos));
        std::uint32_t compression = 0;
        const bool hasGridCompression =
            version >= openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION;
        if (hasGridCompression) compression = in.value<std::uint32_t>("grid compression flags");
        in.skipMetaMap("the grid metadata");
        // Before format 216 the topology precedes the transform; before 219 the transform has
        // another layout (Archive::readGrid, Transform::read).
        std::string mapType;
        if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) {
            mapType = in.shortString(MAX_TYPE_NAME_BYTES, "the grid transform type");
        }
        if (in.position() > std::uint64_t(blockPos)) {
            in.fail("is corrupt: the metadata of grid " + std::to_string(g) +
                    " runs into its data");
        }
        // The root node of the tree: background, tile count, child count, then each tile
        // (coordinates, value, active flag) and each child (coordinates, then at least its two
        // node masks). OpenVDB allocates a child node (~270 KB for a 5_4_3 tree) per count
        // before reading it: bound the counts by the topology bytes (up to blockPos).
        const std::uint64_t mapSize = mapBytes(mapType), valueSize = valueBytes(gridType),
                            maskBytes = rootChildMaskBytes(gridType);
        if (version >= openvdb::OPENVDB_FILE_VERSION_NEW_TRANSFORM && mapSize > 0 &&
            valueSize > 0 && maskBytes > 0 && !isInstance) {
            in.skip(mapSize, "the grid transform");
            in.skip(4, "the tree buffer count");
            in.skip(valueSize, "the tree background");
            const std::uint64_t tiles = in.value<std::uint32_t>("the root tile count");
            const std::uint64_t children = in.value<std::uint32_t>("the root child count");
            const std::uint64_t topologyBytes =
                std::uint64_t(blockPos) - std::min(std::uint64_t(blockPos), in.position());
            const std::uint64_t needed =
                tiles * (ROOT_ENTRY_COORD_BYTES + valueSize + ROOT_TILE_ACTIVE_BYTES) +
                children * (ROOT_ENTRY_COORD_BYTES + maskBytes);
            if (needed > topologyBytes) {
                in.fail("is corrupt: the tree of grid " + std::to_string(g) + " claims " +
                        std::to_string(tiles) + " root tiles and " + std::to_string(children) +
                        " children, more than its " + std::to_string(topologyBytes) +
                        " bytes of topology can hold");
            }
            for (std::uint64_t t = 0; t < tiles; ++t)
                in.skip(ROOT_ENTRY_COORD_BYTES + valueSize + ROOT_TILE_ACTIVE_BYTES, "a root tile");
            // The nodes below the root, for the 5_4_3 trees whose layout this check knows.
            if (hasGridCompression && gridType.find("_5_4_3") != std::string::npos) {
                TreeWalker(in, compression, valueSize, storedValueBytes(gridType, valueSize),
                           int(g))
                    .walk(children, std::uint64_t(blockPos), std::uint64_t(endPos));
            }
        }
        in.seek(std::uint64_t(endPos));
    }
}

} // namespace vdbmatch
