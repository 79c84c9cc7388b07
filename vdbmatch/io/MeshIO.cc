/// @file MeshIO.cc
/// @brief OBJ, PLY and STL mesh readers, polyline reader, OBJ and polyline writers.
#include "MeshIO.h"

#include <vdbmatch/io/InputFile.h>
#include <vdbmatch/io/PathText.h>
#include <vdbmatch/io/TextParsing.h>

#include <openvdb/openvdb.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace vdbmatch {

namespace {

/// Size of the header of a binary STL file: 80 bytes of text and a 32-bit triangle count.
constexpr size_t STL_HEADER_BYTES = 84;
/// Bytes per triangle of a binary STL file: normal, 3 vertices (12 float32) and a 16-bit word.
constexpr size_t STL_TRIANGLE_BYTES = 50;
/// Digits that make a double round-trip through text.
constexpr int ROUND_TRIP_DIGITS = std::numeric_limits<double>::max_digits10;

using detail::quoted;

using detail::isSpace;
using detail::lowerExtension;
using detail::parseDouble;
using detail::ParseError;
using detail::parseInt;
using detail::tokenize;

/// Splits a line into whitespace-separated tokens.
std::vector<std::string_view>
tokens(std::string_view line)
{
    std::vector<std::string_view> out;
    tokenize(line, out);
    return out;
}

/// Iterates over the lines of a text, counting them from 1.
class LineReader
{
public:
    explicit LineReader(std::string_view text) : mText(text) {}
    bool next(std::string_view& line)
    {
        if (mPos >= mText.size()) return false;
        const size_t end = std::min(mText.find('\n', mPos), mText.size());
        line = mText.substr(mPos, end - mPos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        mPos = end + 1;
        ++mLine;
        return true;
    }
    size_t lineNumber() const { return mLine; }
    size_t position() const { return std::min(mPos, mText.size()); }

private:
    std::string_view mText;
    size_t mPos = 0, mLine = 0;
};

/// Appends the fan triangulation (v0, vi, vi+1) of a polygon, dropping triangles that repeat a
/// vertex.
void
addFan(const std::vector<int32_t>& polygon, Surface<3>& s)
{
    for (size_t i = 1; i + 1 < polygon.size(); ++i) {
        const std::array<int32_t, 3> t{polygon[0], polygon[i], polygon[i + 1]};
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        s.elements.push_back(t);
    }
}

////////////////////////////////////////////////////////////////////////////////
// OBJ

Surface<3>
parseObj(const std::string& text, const ParseError& error)
{
    Surface<3> s;
    LineReader lines(text);
    std::string_view line;
    std::vector<int32_t> polygon;
    while (lines.next(line)) {
        const size_t hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
        const auto t = tokens(line);
        if (t.empty()) continue;
        if (t[0] == "v") {
            // x y z, optionally followed by w (4 numbers in all), r g b (scanners, Blender) or
            // r g b a: every extra token must be a number; only x y z are used.
            Vec<3> p;
            bool ok = t.size() >= 4 && t.size() <= 8 && parseDouble(t[1], p[0]) &&
                      parseDouble(t[2], p[1]) && parseDouble(t[3], p[2]);
            for (size_t k = 4; ok && k < t.size(); ++k) {
                double extra = 0;
                ok = parseDouble(t[k], extra);
            }
            if (!ok) {
                error("expected 'v x y z [w | r g b [a]]', got '" + std::string(line) + "'",
                      lines.lineNumber());
            }
            s.points.push_back(p);
        } else if (t[0] == "f") {
            if (t.size() < 4) {
                error("a face needs at least 3 vertices", lines.lineNumber());
            }
            polygon.clear();
            for (size_t k = 1; k < t.size(); ++k) {
                const std::string_view ref = t[k].substr(0, t[k].find('/'));
                int64_t i = 0;
                if (!parseInt(ref, i) || i == 0) {
                    error("invalid vertex index '" + std::string(t[k]) + "'", lines.lineNumber());
                }
                const int64_t n = int64_t(s.points.size());
                const int64_t index = i > 0 ? i - 1 : n + i; // negative: relative to the end
                if (index < 0 || index >= n) {
                    error("vertex index " + std::to_string(i) + " out of range (" +
                              std::to_string(n) + " vertices so far)",
                          lines.lineNumber());
                }
                polygon.push_back(int32_t(index));
            }
            addFan(polygon, s);
        }
    }
    return s;
}

////////////////////////////////////////////////////////////////////////////////
// PLY

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

size_t
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
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

bool
hostIsLittleEndian()
{
    const uint16_t one = 1;
    unsigned char first;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

/// Reads the values of the PLY body, ascii or binary, as doubles.
class PlyBody
{
public:
    PlyBody(std::string_view body, PlyFormat format, const ParseError& error)
        : mBody(body), mFormat(format), mError(error)
    {
        mSwap = format != PlyFormat::Ascii &&
                (format == PlyFormat::BinaryLittleEndian) != hostIsLittleEndian();
    }

    double read(PlyType type)
    {
        if (mFormat == PlyFormat::Ascii) return readAscii(type);
        const size_t n = plySize(type);
        if (mPos + n > mBody.size()) mError("unexpected end of the binary data");
        unsigned char bytes[8];
        std::memcpy(bytes, mBody.data() + mPos, n);
        mPos += n;
        if (mSwap) std::reverse(bytes, bytes + n);
        switch (type) {
        case PlyType::Int8:
            return double(int8_t(bytes[0]));
        case PlyType::UInt8:
            return double(bytes[0]);
        case PlyType::Int16:
            return double(load<int16_t>(bytes));
        case PlyType::UInt16:
            return double(load<uint16_t>(bytes));
        case PlyType::Int32:
            return double(load<int32_t>(bytes));
        case PlyType::UInt32:
            return double(load<uint32_t>(bytes));
        case PlyType::Float32:
            return double(load<float>(bytes));
        case PlyType::Float64:
            return load<double>(bytes);
        }
        return 0.0;
    }

    /// Bytes (binary) or characters (ascii) left: an upper bound on the values left.
    size_t remaining() const { return mBody.size() - mPos; }

private:
    template <typename T> static T load(const unsigned char* bytes)
    {
        T v;
        std::memcpy(&v, bytes, sizeof(T));
        return v;
    }

    double readAscii(PlyType type)
    {
        while (mPos < mBody.size() && isSpace(mBody[mPos]))
            ++mPos;
        const size_t b = mPos;
        while (mPos < mBody.size() && !isSpace(mBody[mPos]))
            ++mPos;
        if (mPos == b) mError("unexpected end of the ascii data");
        const std::string_view token = mBody.substr(b, mPos - b);
        double v = 0.0;
        if (!parseDouble(token, v)) mError("invalid number '" + std::string(token) + "'");
        if (type != PlyType::Float32 && type != PlyType::Float64 && v != std::floor(v)) {
            mError("expected an integer, got '" + std::string(token) + "'");
        }
        return v;
    }

    std::string_view mBody;
    PlyFormat mFormat;
    const ParseError& mError;
    size_t mPos = 0;
    bool mSwap = false;
};

Surface<3>
parsePly(const std::string& text, const ParseError& error)
{
    LineReader lines(text);
    std::string_view line;
    if (!lines.next(line) || line != "ply") error("not a PLY file: the first line is not 'ply'");
    PlyFormat format = PlyFormat::Ascii;
    bool hasFormat = false, ended = false;
    std::vector<PlyElement> elements;
    while (lines.next(line)) {
        const auto t = tokens(line);
        if (t.empty()) continue;
        if (t[0] == "end_header") {
            ended = true;
            break;
        }
        if (t[0] == "comment" || t[0] == "obj_info") continue;
        if (t[0] == "format") {
            if (t.size() != 3) error("malformed format line", lines.lineNumber());
            if (t[1] == "ascii")
                format = PlyFormat::Ascii;
            else if (t[1] == "binary_little_endian")
                format = PlyFormat::BinaryLittleEndian;
            else if (t[1] == "binary_big_endian")
                format = PlyFormat::BinaryBigEndian;
            else
                error("unknown format '" + std::string(t[1]) + "'", lines.lineNumber());
            hasFormat = true;
        } else if (t[0] == "element") {
            int64_t count = 0;
            if (t.size() != 3 || !parseInt(t[2], count) || count < 0) {
                error("malformed element line", lines.lineNumber());
            }
            elements.push_back({std::string(t[1]), uint64_t(count), {}});
        } else if (t[0] == "property") {
            if (elements.empty()) error("property before any element", lines.lineNumber());
            PlyProperty p;
            bool ok = false;
            if (t.size() == 5 && t[1] == "list") {
                p.isList = true;
                p.name = std::string(t[4]);
                ok = plyType(t[2], p.countType) && plyType(t[3], p.type);
            } else if (t.size() == 3) {
                p.name = std::string(t[2]);
                ok = plyType(t[1], p.type);
            }
            if (!ok)
                error("malformed property line '" + std::string(line) + "'", lines.lineNumber());
            elements.back().properties.push_back(p);
        } else {
            error("unknown header line '" + std::string(line) + "'", lines.lineNumber());
        }
    }
    if (!ended) error("the header has no 'end_header' line");
    if (!hasFormat) error("the header has no 'format' line");

    PlyBody body(std::string_view(text).substr(lines.position()), format, error);
    Surface<3> s;
    std::vector<int32_t> polygon;
    bool hasVertices = false;
    for (const PlyElement& e : elements) {
        // Every instance takes at least one byte or character: reject absurd counts early.
        if (e.count > body.remaining() && !e.properties.empty()) {
            error("element '" + e.name + "' has " + std::to_string(e.count) +
                  " instances, more than the data can hold");
        }
        const bool isVertex = e.name == "vertex", isFace = e.name == "face";
        std::array<int, 3> xyz{-1, -1, -1};
        int indices = -1;
        for (size_t k = 0; k < e.properties.size(); ++k) {
            const PlyProperty& p = e.properties[k];
            if (isVertex && !p.isList) {
                if (p.name == "x") xyz[0] = int(k);
                if (p.name == "y") xyz[1] = int(k);
                if (p.name == "z") xyz[2] = int(k);
            }
            if (isFace && p.isList && (p.name == "vertex_indices" || p.name == "vertex_index")) {
                indices = int(k);
            }
        }
        if (isVertex) {
            if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) {
                error("the vertex element lacks an x, y or z property");
            }
            hasVertices = true;
            s.points.reserve(size_t(e.count));
        }
        if (isFace && indices < 0) error("the face element has no vertex_indices list");
        // An element without properties stores nothing: do not count through its instances
        // (a header may claim 9e18 of them).
        if (e.properties.empty()) continue;
        for (uint64_t n = 0; n < e.count; ++n) {
            Vec<3> p = Vec<3>::Zero();
            for (size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& prop = e.properties[k];
                if (!prop.isList) {
                    const double v = body.read(prop.type);
                    for (int a = 0; a < 3; ++a)
                        if (isVertex && xyz[size_t(a)] == int(k)) p[a] = v;
                    continue;
                }
                const double count = body.read(prop.countType);
                if (!(count >= 0.0)) error("negative list length in element '" + e.name + "'");
                // Every entry takes at least one byte or character: a longer list runs past the
                // end.
                if (count > double(body.remaining())) {
                    std::ostringstream m;
                    m << "unexpected end of the data: a list of element '" << e.name << "' claims "
                      << count << " entries, more than the " << body.remaining() << " bytes left";
                    error(m.str());
                }
                const bool keep = isFace && int(k) == indices;
                if (keep) polygon.clear();
                for (uint64_t i = 0; i < uint64_t(count); ++i) {
                    const double v = body.read(prop.type);
                    if (!keep) continue;
                    if (!hasVertices) error("faces come before the vertices");
                    if (!(v >= 0.0) || v >= double(s.points.size())) {
                        error("face " + std::to_string(n) + " refers to vertex " +
                              std::to_string(int64_t(v)) + ", but there are " +
                              std::to_string(s.points.size()) + " vertices");
                    }
                    polygon.push_back(int32_t(v));
                }
                if (keep) {
                    if (polygon.size() < 3) {
                        error("face " + std::to_string(n) + " has fewer than 3 vertices");
                    }
                    addFan(polygon, s);
                }
            }
            if (isVertex) s.points.push_back(p);
        }
    }
    return s;
}

////////////////////////////////////////////////////////////////////////////////
// STL

/// Merges vertices with identical coordinates: triangle soup (3 points per triangle) -> mesh.
Surface<3>
weld(const std::vector<Vec<3>>& soup)
{
    std::vector<uint32_t> order(soup.size());
    for (size_t i = 0; i < order.size(); ++i)
        order[i] = uint32_t(i);
    auto less = [&](uint32_t a, uint32_t b) {
        const Vec<3>&p = soup[a], &q = soup[b];
        return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
    };
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return less(a, b) || (!less(b, a) && a < b); });
    Surface<3> s;
    std::vector<int32_t> id(soup.size());
    for (size_t k = 0; k < order.size(); ++k) {
        if (k == 0 || soup[order[k]] != soup[order[k - 1]]) s.points.push_back(soup[order[k]]);
        id[order[k]] = int32_t(s.points.size() - 1);
    }
    std::vector<int32_t> polygon(3);
    for (size_t t = 0; t + 2 < soup.size(); t += 3) {
        polygon = {id[t], id[t + 1], id[t + 2]};
        addFan(polygon, s);
    }
    return s;
}

/// Rejects NaN and inf coordinates (welding sorts the points: NaN breaks the ordering).
template <int D>
void
checkFinite(const std::vector<Vec<D>>& points, const ParseError& error)
{
    for (size_t i = 0; i < points.size(); ++i) {
        // std::isfinite per coordinate: Eigen's allFinite() computes x - x, which traps with
        // floating-point exceptions enabled (the tests' debug builds).
        bool finite = true;
        for (int a = 0; a < D; ++a)
            finite = finite && std::isfinite(points[i][a]);
        if (!finite) {
            error("point " + std::to_string(i) + " has a non-finite coordinate (NaN or inf)");
        }
    }
}

Surface<3>
parseStl(const std::string& text, const ParseError& error)
{
    std::vector<Vec<3>> soup;
    uint32_t count = 0;
    if (text.size() >= STL_HEADER_BYTES) {
        std::memcpy(&count, text.data() + 80, sizeof(count));
        if (!hostIsLittleEndian()) {
            unsigned char* b = reinterpret_cast<unsigned char*>(&count);
            std::reverse(b, b + 4);
        }
    }
    const bool binary =
        text.size() >= STL_HEADER_BYTES &&
        uint64_t(text.size()) == STL_HEADER_BYTES + uint64_t(count) * STL_TRIANGLE_BYTES;
    if (binary) {
        soup.reserve(size_t(count) * 3);
        for (uint32_t t = 0; t < count; ++t) {
            const char* tri = text.data() + STL_HEADER_BYTES + size_t(t) * STL_TRIANGLE_BYTES;
            for (int v = 0; v < 3; ++v) {
                Vec<3> p;
                for (int a = 0; a < 3; ++a) {
                    unsigned char b[4];
                    std::memcpy(b, tri + 12 * (v + 1) + 4 * a, 4);
                    if (!hostIsLittleEndian()) std::reverse(b, b + 4);
                    float f;
                    std::memcpy(&f, b, 4);
                    p[a] = double(f);
                }
                soup.push_back(p);
            }
        }
        checkFinite(soup, error);
        return weld(soup);
    }
    if (text.compare(0, 5, "solid") != 0) {
        error("neither an ascii STL file (starting with 'solid') nor a binary one (size " +
              std::to_string(text.size()) + " bytes does not match 84 + 50 x triangle count)");
    }
    LineReader lines(text);
    std::string_view line;
    size_t inFacet = 0;
    while (lines.next(line)) {
        const auto t = tokens(line);
        if (t.empty()) continue;
        if (t[0] == "vertex") {
            Vec<3> p;
            if (t.size() != 4 || !parseDouble(t[1], p[0]) || !parseDouble(t[2], p[1]) ||
                !parseDouble(t[3], p[2])) {
                error("expected 'vertex x y z', got '" + std::string(line) + "'",
                      lines.lineNumber());
            }
            soup.push_back(p);
            ++inFacet;
        } else if (t[0] == "endfacet") {
            if (inFacet != 3) error("a facet must have 3 vertices", lines.lineNumber());
            inFacet = 0;
        }
    }
    if (inFacet != 0) error("the last facet is incomplete");
    checkFinite(soup, error);
    return weld(soup);
}

} // namespace

Surface<3>
readMesh(const std::string& path)
{
    const std::string text = readInputFile(path, "readMesh: file " + quoted(path));
    const ParseError error("readMesh", path);
    const std::string ext = lowerExtension(path);
    Surface<3> s;
    if (ext == ".obj")
        s = parseObj(text, error);
    else if (ext == ".ply")
        s = parsePly(text, error);
    else if (ext == ".stl")
        s = parseStl(text, error);
    else
        error("unknown mesh extension '" + ext + "' (expected .obj, .ply or .stl)");
    checkFinite(s.points, error);
    checkSurface(s, "readMesh: file " + quoted(path));
    return s;
}

Surface<2>
readPolyline(const std::string& path)
{
    const std::string text = readInputFile(path, "readPolyline: file " + quoted(path));
    const ParseError error("readPolyline", path);
    const std::string ext = lowerExtension(path);
    if (ext != ".polyline" && ext != ".txt") {
        error("unknown polyline extension '" + ext + "' (expected .polyline or .txt)");
    }
    Surface<2> s;
    size_t curveStart = 0, curveLine = 0;
    auto closeCurve = [&](size_t line) {
        const size_t n = s.points.size() - curveStart;
        if (n == 0) return;
        if (n < 3) {
            error("the curve starting at line " + std::to_string(curveLine) + " has " +
                      std::to_string(n) + " point(s); a closed curve needs at least 3",
                  line);
        }
        for (size_t i = 0; i < n; ++i) {
            s.elements.push_back({int32_t(curveStart + i), int32_t(curveStart + (i + 1) % n)});
        }
        curveStart = s.points.size();
    };
    LineReader lines(text);
    std::string_view line;
    while (lines.next(line)) {
        const size_t hash = line.find('#');
        const bool comment = hash != std::string_view::npos;
        if (comment) line = line.substr(0, hash);
        const auto t = tokens(line);
        if (t.empty()) {
            // A blank line ends the curve; a line holding only a comment does not.
            if (!comment) closeCurve(lines.lineNumber());
            continue;
        }
        Vec<2> p;
        if (t.size() != 2 || !parseDouble(t[0], p[0]) || !parseDouble(t[1], p[1])) {
            error("expected 'x y', got '" + std::string(line) + "'", lines.lineNumber());
        }
        if (s.points.size() == curveStart) curveLine = lines.lineNumber();
        s.points.push_back(p);
    }
    closeCurve(lines.lineNumber());
    checkFinite(s.points, error);
    checkSurface(s, "readPolyline: file " + quoted(path));
    return s;
}

void
writeObj(std::ostream& out, const Surface<3>& surface)
{
    out.precision(ROUND_TRIP_DIGITS);
    for (const Vec<3>& p : surface.points)
        out << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
    for (const auto& t : surface.elements)
        out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
}

void
writeObj(std::ostream& out, const Surface<2>& surface)
{
    out.precision(ROUND_TRIP_DIGITS);
    for (const Vec<2>& p : surface.points)
        out << "v " << p[0] << ' ' << p[1] << " 0\n";
    for (const auto& e : surface.elements)
        out << "l " << e[0] + 1 << ' ' << e[1] + 1 << '\n';
}

void
writePolyline(std::ostream& out, const Surface<2>& surface)
{
    checkSurface(surface, "writePolyline");
    // The two segments of every vertex.
    const size_t n = surface.points.size();
    std::vector<std::array<int32_t, 2>> around(n, {-1, -1});
    for (size_t e = 0; e < surface.elements.size(); ++e) {
        for (const int32_t v : surface.elements[e]) {
            auto& slot = around[size_t(v)];
            (slot[0] < 0 ? slot[0] : slot[1]) = int32_t(e);
        }
    }
    out.precision(ROUND_TRIP_DIGITS);
    out << "# vdbmatch polyline: closed curves, 'x y' per line, blank line between curves\n";
    std::vector<char> done(surface.elements.size(), 0);
    bool first = true;
    for (size_t start = 0; start < surface.elements.size(); ++start) {
        if (done[start]) continue;
        if (!first) out << '\n';
        first = false;
        int32_t e = int32_t(start);
        int32_t v = surface.elements[start][0];
        while (!done[size_t(e)]) {
            done[size_t(e)] = 1;
            const Vec<2>& p = surface.points[size_t(v)];
            out << p[0] << ' ' << p[1] << '\n';
            const auto& seg = surface.elements[size_t(e)];
            v = seg[0] == v ? seg[1] : seg[0];
            const auto& slot = around[size_t(v)];
            e = slot[0] == e ? slot[1] : slot[0];
        }
    }
}

} // namespace vdbmatch
