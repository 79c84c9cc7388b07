/// @file PointTable.cc
/// @brief Reading point tables (.csv, .xyz, .txt) whole and writing them back with new
///        coordinates.
#include "PointTable.h"

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
#include <string_view>
#include <system_error>

namespace vdbmatch {

namespace {

/// Enough characters for any double written by std::to_chars (shortest form).
constexpr std::size_t NUMBER_CHARS = 32;
/// The UTF-8 byte-order mark.
constexpr std::string_view UTF8_BOM = "\xEF\xBB\xBF";

using detail::parseDouble;
using detail::ParseError;
using detail::quoted;

bool
isBlank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

std::string_view
trim(std::string_view s)
{
    while (!s.empty() && isBlank(s.front()))
        s.remove_prefix(1);
    while (!s.empty() && isBlank(s.back()))
        s.remove_suffix(1);
    return s;
}

std::string
lower(std::string_view s)
{
    std::string out(s);
    for (char& c : out)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

/// Splits a line into fields; each field is its content: trimmed, without enclosing quotes (a
/// view into the line).
/// @return false with @a problem set if a quote is not closed or followed by other text
bool
splitFields(std::string_view line, bool comma, std::vector<std::string_view>& fields,
            std::string& problem)
{
    fields.clear();
    if (!comma) {
        std::size_t i = 0;
        while (i < line.size()) {
            while (i < line.size() && isBlank(line[i]))
                ++i;
            const std::size_t b = i;
            while (i < line.size() && !isBlank(line[i]))
                ++i;
            if (i > b) fields.push_back(line.substr(b, i - b));
        }
        return true;
    }
    std::size_t i = 0;
    while (true) {
        while (i < line.size() && isBlank(line[i]))
            ++i;
        if (i < line.size() && line[i] == '"') {
            const std::size_t b = ++i;
            while (true) {
                if (i >= line.size()) {
                    problem = "a quoted field is not closed";
                    return false;
                }
                if (line[i] == '"') {
                    if (i + 1 < line.size() && line[i + 1] == '"') {
                        i += 2; // "" is a quote inside the field
                        continue;
                    }
                    break;
                }
                ++i;
            }
            fields.push_back(line.substr(b, i - b));
            ++i;
            while (i < line.size() && isBlank(line[i]))
                ++i;
            if (i < line.size() && line[i] != ',') {
                problem = "text after the closing quote of a field";
                return false;
            }
        } else {
            const std::size_t b = i;
            while (i < line.size() && line[i] != ',')
                ++i;
            fields.push_back(trim(line.substr(b, i - b)));
        }
        if (i >= line.size()) return true;
        ++i; // the comma
    }
}

} // namespace

PointTable
PointTable::read(const std::string& path, int dimension)
{
    const ParseError error("PointTable::read", path);
    if (dimension != 2 && dimension != 3) {
        error("dimension must be 2 or 3, not " + std::to_string(dimension));
    }
    std::string ext = lower(std::filesystem::path(path).extension().string());
    if (ext != ".csv" && ext != ".xyz" && ext != ".txt") {
        error("unknown point file extension '" + ext + "' (expected .csv, .xyz or .txt)");
    }

    const std::string where = "PointTable::read: file " + quoted(path);
    PointTable table;
    table.mPath = path;
    table.mDimension = dimension;
    table.mBytes = readInputFile(path, where);
    table.parse(ext == ".csv");
    table.mOriginalPositions = table.mPositions;
    return table;
}

void
PointTable::parse(bool comma)
{
    const ParseError error("PointTable::read", mPath);
    std::string_view text(mBytes);
    std::size_t pos = 0, lineNumber = 0;
    if (text.substr(0, UTF8_BOM.size()) == UTF8_BOM) pos = UTF8_BOM.size();
    auto nextLine = [&](std::string_view& line) {
        if (pos >= text.size()) return false;
        const std::size_t end = std::min(text.find('\n', pos), text.size());
        line = text.substr(pos, end - pos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos = end + 1;
        ++lineNumber;
        return true;
    };

    // The header: the first line that is not blank (and, in CSV, not a '#' comment).
    std::string_view line;
    std::vector<std::string_view> fields;
    std::string problem;
    bool hasHeader = false;
    while (nextLine(line)) {
        std::string_view content = trim(line);
        if (content.empty()) continue;
        if (content.front() == '#') {
            if (comma) continue;
            content.remove_prefix(1);
        }
        if (!splitFields(content, comma, fields, problem)) error(problem, lineNumber);
        hasHeader = true;
        break;
    }
    if (!hasHeader) error("missing header line naming the columns (e.g. 'x,y,z')");
    const std::size_t headerLine = lineNumber;
    std::array<int, 3> column{-1, -1, -1};
    static const char* const names[] = {"x", "y", "z"};
    for (std::size_t k = 0; k < fields.size(); ++k) {
        mColumns.emplace_back(fields[k]);
        const std::string name = lower(trim(fields[k]));
        for (int a = 0; a < 3; ++a) {
            if (name != names[a]) continue;
            if (column[size_t(a)] >= 0) {
                error(std::string("column '") + names[a] + "' appears twice", headerLine);
            }
            column[size_t(a)] = int(k);
        }
    }
    for (int a = 0; a < mDimension; ++a) {
        if (column[size_t(a)] < 0) {
            error(std::string("column '") + names[a] + "' missing in the header '" +
                      std::string(line) + "'",
                  headerLine);
        }
    }
    // The axes in the order of their columns (insertion sort of at most 3).
    for (int i = 1; i < mDimension; ++i) {
        for (int k = i; k > 0 && column[size_t(mAxisOrder[size_t(k)])] <
                                     column[size_t(mAxisOrder[size_t(k) - 1])];
             --k) {
            std::swap(mAxisOrder[size_t(k)], mAxisOrder[size_t(k) - 1]);
        }
    }
    const std::size_t columns = fields.size();

    while (nextLine(line)) {
        const std::string_view content = trim(line);
        if (content.empty() || content.front() == '#') continue;
        if (!splitFields(line, comma, fields, problem)) error(problem, lineNumber);
        if (fields.size() != columns) {
            error("expected " + std::to_string(columns) + " fields as in the header, got " +
                      std::to_string(fields.size()),
                  lineNumber);
        }
        openvdb::Vec3d p(0.0);
        for (int a = 0; a < 3; ++a) {
            if (column[size_t(a)] < 0) continue;
            const std::string_view s = fields[size_t(column[size_t(a)])];
            if (!parseDouble(s, p[a]) || !std::isfinite(p[a])) {
                error(std::string("coordinate '") + names[a] + "' is not a finite number: '" +
                          std::string(s) + "'",
                      lineNumber);
            }
            if (a < mDimension) {
                mSlots.push_back({uint64_t(s.data() - text.data()), uint32_t(s.size())});
            }
        }
        mPositions.push_back(p);
    }
}

std::string
PointTable::render() const
{
    const ParseError error("PointTable::write", mPath);
    if (mPositions.size() != mOriginalPositions.size()) {
        error("positions() was resized (" + std::to_string(mPositions.size()) + " positions for " +
              std::to_string(mOriginalPositions.size()) + " points)");
    }
    std::string out;
    out.reserve(mBytes.size() + mBytes.size() / 4);
    std::size_t copied = 0;
    const std::size_t d = std::size_t(mDimension);
    for (std::size_t k = 0; k < mSlots.size(); ++k) {
        const std::size_t point = k / d;
        const int axis = mAxisOrder[k % d];
        const Slot& slot = mSlots[point * d + size_t(axis)];
        out.append(mBytes, copied, std::size_t(slot.begin) - copied);
        copied = std::size_t(slot.begin + slot.length);
        const double value = mPositions[point][axis], original = mOriginalPositions[point][axis];
        if (std::memcmp(&value, &original, sizeof(double)) == 0) {
            out.append(mBytes, std::size_t(slot.begin), slot.length);
            continue;
        }
        if (!std::isfinite(value)) {
            error("the new coordinate " + std::to_string(axis) + " of point " +
                  std::to_string(point) + " is not finite");
        }
        char buf[NUMBER_CHARS];
        const auto r = std::to_chars(buf, buf + sizeof(buf), value);
        out.append(buf, r.ptr);
    }
    out.append(mBytes, copied, mBytes.size() - copied);
    return out;
}

void
PointTable::write(const std::string& path) const
{
    const std::string bytes = render();
    writeFileAtomically(
        path, [&](std::ostream& out) { out.write(bytes.data(), std::streamsize(bytes.size())); });
}

} // namespace vdbmatch
