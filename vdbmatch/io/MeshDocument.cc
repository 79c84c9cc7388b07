/// @file MeshDocument.cc
/// @brief Reading OBJ, PLY and STL files whole and writing them back with new coordinates.
#include "MeshDocument.h"

#include "AtomicFile.h"

#include <vdbmatch/io/InputFile.h>
#include <vdbmatch/io/PathText.h>
#include <vdbmatch/io/TextParsing.h>

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <system_error>

namespace vdbmatch {

namespace {

/// Size of the header of a binary STL file: 80 bytes of text and a 32-bit triangle count.
constexpr std::size_t STL_HEADER_BYTES = 84;
/// Bytes of the free text at the start of a binary STL file.
constexpr std::size_t STL_TEXT_BYTES = 80;
/// Bytes per triangle of a binary STL file: normal, 3 vertices (12 float32) and a 16-bit word.
constexpr std::size_t STL_TRIANGLE_BYTES = 50;
/// Bytes of one float32 coordinate in binary STL.
constexpr std::size_t STL_FLOAT_BYTES = 4;
/// Enough characters for any double or float written by std::to_chars (shortest form).
constexpr std::size_t NUMBER_CHARS = 32;

using detail::quoted;

using detail::isSpace;
using detail::lowerExtension;
using detail::parseDouble;
using detail::ParseError;
using detail::parseInt;
using detail::tokenize;

/// Iterates over the lines of a text, counting them from 1; lines exclude "\n" and "\r\n".
class LineReader
{
public:
    explicit LineReader(std::string_view text) : mText(text) {}
    bool next(std::string_view& line)
    {
        if (mPos >= mText.size()) return false;
        const std::size_t end = std::min(mText.find('\n', mPos), mText.size());
        line = mText.substr(mPos, end - mPos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        mPos = end + 1;
        ++mLine;
        return true;
    }
    std::size_t lineNumber() const { return mLine; }
    /// Offset of the next line.
    std::size_t position() const { return std::min(mPos, mText.size()); }

private:
    std::string_view mText;
    std::size_t mPos = 0, mLine = 0;
};

bool
hostIsLittleEndian()
{
    const uint16_t one = 1;
    unsigned char first;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

/// Same bits (so -0 differs from 0, and a NaN equals itself).
bool
sameBits(double a, double b)
{
    return std::memcmp(&a, &b, sizeof(double)) == 0;
}

template <typename T>
void
appendNumber(std::string& out, T v)
{
    char buf[NUMBER_CHARS];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out.append(buf, r.ptr);
}

template <typename T>
void
appendBinary(std::string& out, T v, bool swap)
{
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (swap) std::reverse(b, b + sizeof(T));
    out.append(b, sizeof(T));
}

template <typename T>
T
loadBinary(const char* p, bool swap)
{
    char b[sizeof(T)];
    std::memcpy(b, p, sizeof(T));
    if (swap) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
}

////////////////////////////////////////////////////////////////////////////////
// PLY header

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool
plyType(std::string_view name, PlyType& type)
{
    static const std::pair<const char*, PlyType> table[] = {
        {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (const auto& entry : table) {
        if (name == entry.first) {
            type = entry.second;
            return true;
        }
    }
    return false;
}

std::size_t
plySize(PlyType t)
{
    switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
        return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
        return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
        return 4;
    case PlyType::Float64:
        return 8;
    }
    return 1;
}

bool
isFloating(PlyType t)
{
    return t == PlyType::Float32 || t == PlyType::Float64;
}

struct PlyProperty
{
    std::string name;
    bool isList = false;
    PlyType countType = PlyType::UInt8;
    PlyType type = PlyType::Float32;
};

struct PlyElement
{
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
    std::size_t lastLineEnd = 0; ///< offset after the element's last header line
    bool lastLineIsCrLf = false; ///< that line ends with "\r\n"
};

bool
isIdentifier(const std::string& name)
{
    if (name.empty()) return false;
    const auto first = static_cast<unsigned char>(name[0]);
    if (!(std::isalpha(first) || name[0] == '_')) return false;
    return std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
    });
}

/// Reads values of the PLY body, ascii or binary, remembering where each one is stored.
class PlyCursor
{
public:
    PlyCursor(std::string_view text, std::size_t start, bool ascii, bool swap,
              const ParseError& error)
        : mText(text), mPos(start), mAscii(ascii), mSwap(swap), mError(error)
    {
    }

    /// Reads one value; @a begin and @a length receive where it is stored.
    double read(PlyType type, std::size_t& begin, std::size_t& length)
    {
        if (mAscii) {
            const std::string_view token = nextToken(begin);
            length = token.size();
            double v = 0.0;
            if (!parseDouble(token, v)) mError("invalid number '" + std::string(token) + "'");
            if (!isFloating(type) && v != std::floor(v)) {
                mError("expected an integer, got '" + std::string(token) + "'");
            }
            // The value the file declares: a float property holds a float.
            return type == PlyType::Float32 ? double(float(v)) : v;
        }
        length = plySize(type);
        if (length > mText.size() - mPos) mError("unexpected end of the binary data");
        begin = mPos;
        const char* p = mText.data() + mPos;
        mPos += length;
        switch (type) {
        case PlyType::Int8:
            return double(int8_t(*p));
        case PlyType::UInt8:
            return double(uint8_t(*p));
        case PlyType::Int16:
            return double(loadBinary<int16_t>(p, mSwap));
        case PlyType::UInt16:
            return double(loadBinary<uint16_t>(p, mSwap));
        case PlyType::Int32:
            return double(loadBinary<int32_t>(p, mSwap));
        case PlyType::UInt32:
            return double(loadBinary<uint32_t>(p, mSwap));
        case PlyType::Float32:
            return double(loadBinary<float>(p, mSwap));
        case PlyType::Float64:
            return loadBinary<double>(p, mSwap);
        }
        return 0.0;
    }

    double read(PlyType type)
    {
        std::size_t begin, length;
        return read(type, begin, length);
    }

    /// Skips @a n values of @a type.
    void skip(PlyType type, uint64_t n)
    {
        if (mAscii) {
            std::size_t begin;
            for (uint64_t i = 0; i < n; ++i)
                nextToken(begin);
            return;
        }
        const uint64_t bytes = n * plySize(type);
        if (n > mText.size() || bytes > mText.size() - mPos) {
            mError("unexpected end of the binary data");
        }
        mPos += std::size_t(bytes);
    }

    /// Offset after the last value read.
    std::size_t position() const { return mPos; }
    std::size_t remaining() const { return mText.size() - mPos; }

private:
    std::string_view nextToken(std::size_t& begin)
    {
        while (mPos < mText.size() && isSpace(mText[mPos]))
            ++mPos;
        begin = mPos;
        while (mPos < mText.size() && !isSpace(mText[mPos]))
            ++mPos;
        if (mPos == begin) mError("unexpected end of the ascii data");
        return mText.substr(begin, mPos - begin);
    }

    std::string_view mText;
    std::size_t mPos;
    bool mAscii, mSwap;
    const ParseError& mError;
};

} // namespace

////////////////////////////////////////////////////////////////////////////////

MeshDocument
MeshDocument::read(const std::string& path)
{
    MeshDocument doc;
    doc.mPath = path;
    doc.mBytes = readInputFile(path, "MeshDocument::read: file " + quoted(path));
    const ParseError error("MeshDocument::read", path);
    const std::string ext = lowerExtension(path);
    if (ext != ".obj" && ext != ".ply" && ext != ".stl") {
        error("unknown mesh extension '" + ext + "' (expected .obj, .ply or .stl)");
    }
    if (doc.mBytes.empty()) error("the file is empty");
    if (ext == ".obj") {
        doc.mFormat = Format::Obj;
        doc.parseObj();
    } else if (ext == ".ply") {
        doc.mFormat = Format::Ply;
        doc.parsePly();
    } else {
        doc.mFormat = Format::Stl;
        doc.parseStl();
    }
    doc.mOriginalPositions = doc.mPositions;
    doc.mOriginalNormals = doc.mNormals;
    if (doc.mNormalUsed.size() != doc.mNormals.size())
        doc.mNormalUsed.assign(doc.mNormals.size(), 1);
    return doc;
}

////////////////////////////////////////////////////////////////////////////////
// OBJ

void
MeshDocument::parseObj()
{
    const ParseError error("MeshDocument::read", mPath);
    const std::string_view text(mBytes);
    LineReader lines(text);
    std::string_view line;
    std::vector<std::string_view> t;
    auto offset = [&](std::string_view token) { return uint64_t(token.data() - text.data()); };
    // Reads 3 coordinates from tokens 1..3 into @a p and their slots into @a layout.
    auto readTriple = [&](Layout& layout, openvdb::Vec3d& p) {
        for (int a = 0; a < 3; ++a) {
            const std::string_view s = t[size_t(a) + 1];
            if (!parseDouble(s, p[a])) return false;
            layout.slots.push_back({offset(s), uint32_t(s.size())});
        }
        return true;
    };
    while (lines.next(line)) {
        const std::size_t hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
        tokenize(line, t);
        if (t.empty()) continue;
        if (t[0] == "v") {
            openvdb::Vec3d p;
            if (t.size() < 4 || !readTriple(mPositionLayout, p)) {
                error("expected 'v x y z', got '" + std::string(line) + "'", lines.lineNumber());
            }
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
                error("non-finite vertex coordinate", lines.lineNumber());
            }
            mPositions.push_back(p);
        } else if (t[0] == "vn") {
            openvdb::Vec3d n;
            if (t.size() != 4 || !readTriple(mNormalLayout, n)) {
                error("expected 'vn x y z', got '" + std::string(line) + "'", lines.lineNumber());
            }
            mNormals.push_back(n);
            mNormalAnchors.push_back(openvdb::Vec3d(0.0));
            mNormalUsed.push_back(0);
        } else if (t[0] == "f") {
            if (t.size() < 4) error("a face needs at least 3 vertices", lines.lineNumber());
            ++mFaceCount;
            for (std::size_t k = 1; k < t.size(); ++k) {
                // i, i/t, i//n or i/t/n
                const std::string_view ref = t[k];
                const std::size_t slash1 = ref.find('/');
                auto resolve = [&](std::string_view s, std::size_t n, const char* what) {
                    int64_t i = 0;
                    if (!parseInt(s, i) || i == 0) {
                        error(std::string("invalid ") + what + " index in '" + std::string(ref) +
                                  "'",
                              lines.lineNumber());
                    }
                    const int64_t index = i > 0 ? i - 1 : int64_t(n) + i; // negative: relative
                    if (index < 0 || index >= int64_t(n)) {
                        error(std::string(what) + " index " + std::to_string(i) +
                                  " out of range (" + std::to_string(n) + " so far)",
                              lines.lineNumber());
                    }
                    return std::size_t(index);
                };
                const std::size_t v = resolve(ref.substr(0, slash1), mPositions.size(), "vertex");
                if (slash1 == std::string_view::npos) continue;
                const std::size_t slash2 = ref.find('/', slash1 + 1);
                if (slash2 == std::string_view::npos) continue;
                const std::string_view nref = ref.substr(slash2 + 1);
                if (nref.empty()) continue;
                const std::size_t n = resolve(nref, mNormals.size(), "normal");
                if (!mNormalUsed[n]) {
                    mNormalUsed[n] = 1;
                    mNormalAnchors[n] = mPositions[v];
                }
            }
        }
    }
}

////////////////////////////////////////////////////////////////////////////////
// PLY

void
MeshDocument::parsePly()
{
    const ParseError error("MeshDocument::read", mPath);
    const std::string_view text(mBytes);
    LineReader lines(text);
    std::string_view line;
    if (!lines.next(line) || line != "ply") error("not a PLY file: the first line is not 'ply'");
    bool hasFormat = false, ended = false;
    std::vector<PlyElement> elements;
    std::vector<std::string_view> t;
    while (lines.next(line)) {
        tokenize(line, t);
        if (t.empty()) continue;
        if (t[0] == "end_header") {
            ended = true;
            break;
        }
        if (t[0] == "comment" || t[0] == "obj_info") continue;
        if (t[0] == "format") {
            if (t.size() != 3) error("malformed format line", lines.lineNumber());
            if (t[1] == "ascii")
                mEncoding = Encoding::Text;
            else if (t[1] == "binary_little_endian")
                mEncoding = Encoding::BinaryLittleEndian;
            else if (t[1] == "binary_big_endian")
                mEncoding = Encoding::BinaryBigEndian;
            else
                error("unknown format '" + std::string(t[1]) + "'", lines.lineNumber());
            hasFormat = true;
        } else if (t[0] == "element") {
            int64_t count = 0;
            if (t.size() != 3 || !parseInt(t[2], count) || count < 0) {
                error("malformed element line", lines.lineNumber());
            }
            elements.push_back({std::string(t[1]), uint64_t(count), {}, 0, false});
        } else if (t[0] == "property") {
            if (elements.empty()) error("property before any element", lines.lineNumber());
            PlyProperty p;
            bool ok = false;
            if (t.size() == 5 && t[1] == "list") {
                p.isList = true;
                p.name = std::string(t[4]);
                ok =
                    plyType(t[2], p.countType) && plyType(t[3], p.type) && !isFloating(p.countType);
            } else if (t.size() == 3) {
                p.name = std::string(t[2]);
                ok = plyType(t[1], p.type);
            }
            if (!ok) {
                error("malformed property line '" + std::string(line) + "'", lines.lineNumber());
            }
            elements.back().properties.push_back(p);
        } else {
            error("unknown header line '" + std::string(line) + "'", lines.lineNumber());
        }
        if (t[0] == "element" || t[0] == "property") {
            elements.back().lastLineEnd = lines.position();
            const std::size_t end = lines.position();
            elements.back().lastLineIsCrLf =
                end >= 2 && text[end - 1] == '\n' && text[end - 2] == '\r';
        }
    }
    if (!ended) error("the header has no 'end_header' line");
    if (!hasFormat) error("the header has no 'format' line");

    const bool ascii = mEncoding == Encoding::Text;
    const bool swap = !ascii && (mEncoding == Encoding::BinaryLittleEndian) != hostIsLittleEndian();
    PlyCursor body(text, lines.position(), ascii, swap, error);
    bool hasVertices = false;
    for (const PlyElement& e : elements) {
        const bool isVertex = e.name == "vertex" && !hasVertices;
        if (e.name == "face") mFaceCount += std::size_t(e.count);
        // Reject absurd counts before allocating anything: every instance takes at least its
        // fixed-size values (binary), or one character per value (ascii).
        uint64_t minBytes = 0;
        for (const PlyProperty& p : e.properties)
            minBytes += ascii ? 1 : plySize(p.isList ? p.countType : p.type);
        if (minBytes > 0 && e.count > body.remaining() / minBytes) {
            error("element '" + e.name + "' has " + std::to_string(e.count) +
                  " instances, more than the data can hold");
        }
        std::array<int, 3> xyz{-1, -1, -1}, nxyz{-1, -1, -1};
        if (isVertex) {
            hasVertices = true;
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& p = e.properties[k];
                mVertexPropertyNames.push_back(p.name);
                if (p.isList) continue;
                static const char* const names[] = {"x", "y", "z", "nx", "ny", "nz"};
                for (int a = 0; a < 6; ++a) {
                    if (p.name != names[a]) continue;
                    (a < 3 ? xyz[size_t(a)] : nxyz[size_t(a - 3)]) = int(k);
                }
            }
            for (int a = 0; a < 3; ++a) {
                if (xyz[size_t(a)] < 0) error("the vertex element lacks an x, y or z property");
                if (!isFloating(e.properties[size_t(xyz[size_t(a)])].type)) {
                    error("vertex coordinates must be float or double, not an integer type");
                }
            }
            const bool hasNormals = std::all_of(nxyz.begin(), nxyz.end(), [&](int k) {
                return k >= 0 && isFloating(e.properties[size_t(k)].type);
            });
            if (!hasNormals) nxyz = {-1, -1, -1};
            // Slots of each vertex are recorded in file (property) order.
            auto setOrder = [&](Layout& layout, const std::array<int, 3>& columns) {
                std::array<int, 3> order{0, 1, 2};
                std::sort(order.begin(), order.end(),
                          [&](int a, int b) { return columns[size_t(a)] < columns[size_t(b)]; });
                layout.axisOrder = order;
                for (int a = 0; a < 3; ++a) {
                    layout.types[size_t(a)] =
                        e.properties[size_t(columns[size_t(a)])].type == PlyType::Float32
                            ? Scalar::Float32
                            : Scalar::Float64;
                }
            };
            setOrder(mPositionLayout, xyz);
            if (hasNormals) setOrder(mNormalLayout, nxyz);
            mHeaderInsert = e.lastLineEnd;
            mHeaderNewline = e.lastLineIsCrLf ? "\r\n" : "\n";
            mPositions.resize(std::size_t(e.count));
            mPositionLayout.slots.resize(std::size_t(e.count) * 3);
            mRowEnds.resize(std::size_t(e.count));
            if (hasNormals) {
                mNormals.resize(std::size_t(e.count));
                mNormalLayout.slots.resize(std::size_t(e.count) * 3);
            }
        }
        // An element without properties stores nothing: do not count through its instances
        // (a header may claim 9e18 of them).
        if (e.properties.empty()) continue;
        for (uint64_t n = 0; n < e.count; ++n) {
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& prop = e.properties[k];
                if (prop.isList) {
                    const double count = body.read(prop.countType);
                    if (count < 0.0) error("negative list length in element '" + e.name + "'");
                    // Every entry takes at least one byte or character: a longer list runs past the
                    // end.
                    if (count > double(body.remaining())) {
                        std::ostringstream m;
                        m << "unexpected end of the data: a list of element '" << e.name
                          << "' claims " << count << " entries, more than the " << body.remaining()
                          << " bytes left";
                        error(m.str());
                    }
                    body.skip(prop.type, uint64_t(count));
                    continue;
                }
                if (!isVertex) {
                    body.skip(prop.type, 1);
                    continue;
                }
                std::size_t begin = 0, length = 0;
                const double v = body.read(prop.type, begin, length);
                for (int a = 0; a < 3; ++a) {
                    const Slot slot{uint64_t(begin), uint32_t(length)};
                    if (xyz[size_t(a)] == int(k)) {
                        if (!std::isfinite(v)) {
                            error("vertex " + std::to_string(n) + " has a non-finite coordinate");
                        }
                        mPositions[std::size_t(n)][a] = v;
                        mPositionLayout.slots[std::size_t(n) * 3 + size_t(a)] = slot;
                    }
                    if (nxyz[size_t(a)] == int(k)) {
                        mNormals[std::size_t(n)][a] = v;
                        mNormalLayout.slots[std::size_t(n) * 3 + size_t(a)] = slot;
                    }
                }
            }
            if (isVertex) mRowEnds[std::size_t(n)] = body.position();
        }
    }
    if (!hasVertices) error("the file has no vertex element");
    mNormalAnchors = mNormals.empty() ? std::vector<openvdb::Vec3d>() : mPositions;
}

////////////////////////////////////////////////////////////////////////////////
// STL

void
MeshDocument::parseStl()
{
    const ParseError error("MeshDocument::read", mPath);
    const std::string_view text(mBytes);
    uint32_t count = 0;
    if (text.size() >= STL_HEADER_BYTES) {
        count = loadBinary<uint32_t>(text.data() + STL_TEXT_BYTES, !hostIsLittleEndian());
    }
    const bool binary =
        text.size() >= STL_HEADER_BYTES &&
        uint64_t(text.size()) == STL_HEADER_BYTES + uint64_t(count) * STL_TRIANGLE_BYTES;
    mFaceCount = 0;
    if (binary) {
        mEncoding = Encoding::BinaryLittleEndian;
        const bool swap = !hostIsLittleEndian();
        for (Layout* layout : {&mPositionLayout, &mNormalLayout})
            layout->types = {Scalar::Float32, Scalar::Float32, Scalar::Float32};
        mPositions.resize(std::size_t(count) * 3);
        mNormals.resize(count);
        mNormalAnchors.resize(count);
        mPositionLayout.slots.resize(std::size_t(count) * 9);
        mNormalLayout.slots.resize(std::size_t(count) * 3);
        for (uint32_t f = 0; f < count; ++f) {
            const std::size_t tri = STL_HEADER_BYTES + std::size_t(f) * STL_TRIANGLE_BYTES;
            openvdb::Vec3d centroid(0.0);
            // Normal first, then the 3 corners, 3 floats each.
            for (std::size_t v = 0; v < 4; ++v) {
                for (int a = 0; a < 3; ++a) {
                    const std::size_t at = tri + (3 * v + size_t(a)) * STL_FLOAT_BYTES;
                    const double x = double(loadBinary<float>(text.data() + at, swap));
                    const Slot slot{uint64_t(at), uint32_t(STL_FLOAT_BYTES)};
                    if (v == 0) {
                        mNormals[f][a] = x;
                        mNormalLayout.slots[std::size_t(f) * 3 + size_t(a)] = slot;
                        continue;
                    }
                    if (!std::isfinite(x)) {
                        error("facet " + std::to_string(f) + " has a non-finite coordinate");
                    }
                    const std::size_t corner = std::size_t(f) * 3 + v - 1;
                    mPositions[corner][a] = x;
                    mPositionLayout.slots[corner * 3 + size_t(a)] = slot;
                    centroid[a] += x;
                }
            }
            mNormalAnchors[f] = centroid / 3.0;
        }
        mFaceCount = count;
        return;
    }
    if (text.compare(0, 5, "solid") != 0) {
        error("neither an ascii STL file (starting with 'solid') nor a binary one (size " +
              std::to_string(text.size()) + " bytes does not match 84 + 50 x triangle count)");
    }
    mEncoding = Encoding::Text;
    LineReader lines(text);
    std::string_view line;
    std::vector<std::string_view> t;
    auto offset = [&](std::string_view token) { return uint64_t(token.data() - text.data()); };
    bool inFacet = false;
    std::size_t corners = 0;
    while (lines.next(line)) {
        tokenize(line, t);
        if (t.empty()) continue;
        if (t[0] == "facet") {
            openvdb::Vec3d n;
            if (inFacet) error("'facet' inside a facet", lines.lineNumber());
            if (t.size() != 5 || t[1] != "normal" || !parseDouble(t[2], n[0]) ||
                !parseDouble(t[3], n[1]) || !parseDouble(t[4], n[2])) {
                error("expected 'facet normal nx ny nz', got '" + std::string(line) + "'",
                      lines.lineNumber());
            }
            for (int a = 0; a < 3; ++a)
                mNormalLayout.slots.push_back(
                    {offset(t[size_t(a) + 2]), uint32_t(t[size_t(a) + 2].size())});
            mNormals.push_back(n);
            inFacet = true;
            corners = 0;
        } else if (t[0] == "vertex") {
            openvdb::Vec3d p;
            if (!inFacet || corners == 3)
                error("a vertex outside a facet or a 4th corner", lines.lineNumber());
            if (t.size() != 4 || !parseDouble(t[1], p[0]) || !parseDouble(t[2], p[1]) ||
                !parseDouble(t[3], p[2])) {
                error("expected 'vertex x y z', got '" + std::string(line) + "'",
                      lines.lineNumber());
            }
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
                error("non-finite vertex coordinate", lines.lineNumber());
            }
            for (int a = 0; a < 3; ++a)
                mPositionLayout.slots.push_back(
                    {offset(t[size_t(a) + 1]), uint32_t(t[size_t(a) + 1].size())});
            mPositions.push_back(p);
            ++corners;
        } else if (t[0] == "endfacet") {
            if (!inFacet || corners != 3) error("a facet must have 3 vertices", lines.lineNumber());
            const std::size_t last = mPositions.size();
            mNormalAnchors.push_back(
                (mPositions[last - 3] + mPositions[last - 2] + mPositions[last - 1]) / 3.0);
            inFacet = false;
            ++mFaceCount;
        }
    }
    if (inFacet) error("the last facet is incomplete");
}

////////////////////////////////////////////////////////////////////////////////
// Editing and writing

void
MeshDocument::addVertexProperty(const std::string& name, std::vector<float> values)
{
    const ParseError error("MeshDocument::addVertexProperty", mPath);
    if (mFormat != Format::Ply) error("vertex properties can only be added to a PLY file");
    if (!isIdentifier(name)) error("invalid property name " + quoted(name));
    const bool taken = std::find(mVertexPropertyNames.begin(), mVertexPropertyNames.end(), name) !=
                           mVertexPropertyNames.end() ||
                       std::any_of(mAddedProperties.begin(), mAddedProperties.end(),
                                   [&](const auto& p) { return p.first == name; });
    if (taken) error("the vertex element already has a property " + quoted(name));
    if (values.size() != mPositions.size()) {
        error("property " + quoted(name) + " has " + std::to_string(values.size()) +
              " values for " + std::to_string(mPositions.size()) + " vertices");
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (!std::isfinite(values[i])) {
            error("property " + quoted(name) + " is not finite at vertex " + std::to_string(i));
        }
    }
    mAddedProperties.emplace_back(name, std::move(values));
}

void
MeshDocument::appendValue(std::string& out, const Layout& layout, std::size_t entry, int axis,
                          double value, double original) const
{
    const Slot& slot = layout.slots[entry * 3 + size_t(axis)];
    if (sameBits(value, original)) {
        out.append(mBytes, std::size_t(slot.begin), slot.length);
        return;
    }
    const bool isFloat = layout.types[size_t(axis)] == Scalar::Float32;
    if (!std::isfinite(value) || (isFloat && !std::isfinite(float(value)))) {
        ParseError("MeshDocument::write", mPath)(
            "the new value of coordinate " + std::to_string(axis) + " of entry " +
            std::to_string(entry) + " is not finite" + (isFloat ? " as a float" : ""));
    }
    if (mEncoding == Encoding::Text) {
        if (isFloat)
            appendNumber(out, float(value));
        else
            appendNumber(out, value);
        return;
    }
    const bool swap = (mEncoding == Encoding::BinaryLittleEndian) != hostIsLittleEndian();
    if (isFloat)
        appendBinary(out, float(value), swap);
    else
        appendBinary(out, value, swap);
}

std::string
MeshDocument::render() const
{
    const ParseError error("MeshDocument::write", mPath);
    if (mPositions.size() != mOriginalPositions.size() ||
        mNormals.size() != mOriginalNormals.size()) {
        error("positions() or normals() were resized (" + std::to_string(mPositions.size()) +
              " positions for " + std::to_string(mOriginalPositions.size()) + ", " +
              std::to_string(mNormals.size()) + " normals for " +
              std::to_string(mOriginalNormals.size()) + ")");
    }
    const bool text = mEncoding == Encoding::Text;
    const bool swap = !text && (mEncoding == Encoding::BinaryLittleEndian) != hostIsLittleEndian();
    std::string out;
    out.reserve(mBytes.size() + mBytes.size() / 4 +
                mAddedProperties.size() * mPositions.size() * 16);
    std::size_t copied = 0;
    auto copyTo = [&](std::size_t offset) {
        out.append(mBytes, copied, offset - copied);
        copied = offset;
    };
    if (!mAddedProperties.empty()) {
        copyTo(std::size_t(mHeaderInsert));
        for (const auto& p : mAddedProperties)
            out += "property float " + p.first + mHeaderNewline;
    }
    // Three streams sorted by offset: position slots, normal slots, vertex row ends (insertions).
    const std::size_t positionSlots = mPositionLayout.slots.size();
    const std::size_t normalSlots = mNormalLayout.slots.size();
    const std::size_t rows = mAddedProperties.empty() ? 0 : mRowEnds.size();
    constexpr uint64_t NONE = std::numeric_limits<uint64_t>::max();
    std::size_t ip = 0, in = 0, ir = 0;
    auto slotOffset = [](const Layout& layout, std::size_t k, std::size_t total) {
        if (k >= total) return NONE;
        return layout.slots[(k / 3) * 3 + size_t(layout.axisOrder[k % 3])].begin;
    };
    while (true) {
        const uint64_t p = slotOffset(mPositionLayout, ip, positionSlots);
        const uint64_t n = slotOffset(mNormalLayout, in, normalSlots);
        const uint64_t r = ir < rows ? mRowEnds[ir] : NONE;
        if (p == NONE && n == NONE && r == NONE) break;
        if (r <= p && r <= n) {
            copyTo(std::size_t(r));
            for (const auto& prop : mAddedProperties) {
                if (text) {
                    out += ' ';
                    appendNumber(out, prop.second[ir]);
                } else {
                    appendBinary(out, prop.second[ir], swap);
                }
            }
            ++ir;
            continue;
        }
        const bool isPosition = p < n;
        const Layout& layout = isPosition ? mPositionLayout : mNormalLayout;
        std::size_t& k = isPosition ? ip : in;
        const std::size_t entry = k / 3;
        const int axis = layout.axisOrder[k % 3];
        const Slot& slot = layout.slots[entry * 3 + size_t(axis)];
        copyTo(std::size_t(slot.begin));
        const auto& values = isPosition ? mPositions : mNormals;
        const auto& originals = isPosition ? mOriginalPositions : mOriginalNormals;
        appendValue(out, layout, entry, axis, values[entry][axis], originals[entry][axis]);
        copied = std::size_t(slot.begin + slot.length);
        ++k;
    }
    copyTo(mBytes.size());
    return out;
}

void
MeshDocument::write(const std::string& path) const
{
    const std::string bytes = render();
    writeFileAtomically(
        path, [&](std::ostream& out) { out.write(bytes.data(), std::streamsize(bytes.size())); });
}

} // namespace vdbmatch
