// Reading and writing vocabulary files: DBoW2's text format and heslam's binary format.
#include "components/core/place/vocabulary_io.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "runtime/atomic_file.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// The binary format is little-endian and read with plain copies.
static_assert(std::endian::native == std::endian::little, "the binary vocabulary reader assumes a little-endian host");

constexpr std::array<char, 8> kBinaryMagic = {'H', 'E', 'S', 'L', 'A', 'M', 'V', 'B'};
// magic, version, k, L, scoring, weighting, reserved (u32 each), node count (u64).
constexpr std::size_t kBinaryHeaderBytes = 8 + 6 * 4 + 8;
// Per node: parent u32, is_leaf u8, descriptor 32 x u8, weight f32.
constexpr std::size_t kBinaryBytesPerNode = 4 + 1 + 32 + 4;
constexpr std::size_t kChecksumBytes = 8;
// DBoW2 limits its text header to these ranges; anything else is a corrupt or foreign file.
constexpr int kMaxTextBranching = 1 << 16;
constexpr int kMaxTextLevels = 255;
constexpr int kMaxScoring = static_cast<int>(BowScoring::kDotProduct);
constexpr int kMaxWeighting = static_cast<int>(BowWeighting::kBinary);
// A node's line in the text format is about this long (32 descriptor bytes of up to 4 characters):
// reserved up front so the text is assembled without repeated growth.
constexpr std::size_t kTextBytesPerNode = 160;

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error("vocabulary " + path.string() + ": " + what);
}

[[noreturn]] void fail_at(const fs::path& path, std::size_t line, const std::string& what) {
  throw std::runtime_error("vocabulary " + path.string() + ":" + std::to_string(line) + ": " + what);
}

std::vector<char> read_whole_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open file");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) fail(path, "cannot read file");
  in.seekg(0, std::ios::beg);
  std::vector<char> data(static_cast<std::size_t>(size));
  if (size > 0 && !in.read(data.data(), size)) fail(path, "cannot read file");
  return data;
}

// A whole file mapped read-only (prefaulted): the binary loader reads it in place, no copy.
class MappedFile {
 public:
  explicit MappedFile(const fs::path& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) fail(path, "cannot open file");
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
      ::close(fd);
      fail(path, "cannot read file");
    }
    size_ = static_cast<std::size_t>(st.st_size);
    if (size_ > 0) {
      void* data = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (data == MAP_FAILED) {
        ::close(fd);
        fail(path, "cannot map file");
      }
      data_ = static_cast<const char*>(data);
    }
    ::close(fd);
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  std::span<const char> bytes() const { return {data_, size_}; }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

// Both writers replace the file whole (runtime/atomic_file.hpp: "<path>.tmp", renamed over it), so a
// reader never sees half a file.
void write_atomically(const fs::path& path, std::string_view bytes) {
  try {
    runtime::replace_file_contents(path, bytes);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string("vocabulary ") + error.what());
  }
}

// --- text ------------------------------------------------------------------------------------

// Splits a line into whitespace-separated fields without allocating.
class FieldReader {
 public:
  explicit FieldReader(std::string_view line) : rest_(line) {}

  bool next(std::string_view& field) {
    std::size_t begin = 0;
    while (begin < rest_.size() && is_space(rest_[begin])) ++begin;
    if (begin == rest_.size()) return false;
    std::size_t end = begin;
    while (end < rest_.size() && !is_space(rest_[end])) ++end;
    field = rest_.substr(begin, end - begin);
    rest_ = rest_.substr(end);
    return true;
  }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }
  std::string_view rest_;
};

template <typename T>
bool parse_number(std::string_view field, T& value) {
  const char* begin = field.data();
  const char* end = field.data() + field.size();
  if (begin != end && *begin == '+') ++begin;  // from_chars rejects a leading '+'
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  return ec == std::errc() && ptr == end;
}

// A field as it appears in an error message: quoted, long ones cut.
std::string quoted(std::string_view field) {
  constexpr std::size_t kMaxQuoted = 40;
  std::string out(1, '\'');
  out.append(field.substr(0, kMaxQuoted));
  out.push_back('\'');
  return out;
}

struct TextHeader {
  int branching = 0;
  int levels = 0;
  int scoring = 0;
  int weighting = 0;
};

TextHeader parse_text_header(const fs::path& path, std::string_view line) {
  const char* expected = "expected header 'k L scoring weighting'";
  FieldReader fields(line);
  std::array<int, 4> values{};
  std::string_view field;
  for (int& value : values) {
    if (!fields.next(field)) fail_at(path, 1, std::string(expected) + ", got " + quoted(line));
    if (!parse_number(field, value))
      fail_at(path, 1, std::string(expected) + ", " + quoted(field) + " is not an integer");
  }
  if (fields.next(field)) fail_at(path, 1, std::string(expected) + ", got extra field " + quoted(field));
  TextHeader header{values[0], values[1], values[2], values[3]};
  if (header.branching < 1 || header.branching > kMaxTextBranching) {
    fail_at(path, 1,
            "branching factor k = " + std::to_string(header.branching) + " is out of range 1.." +
                std::to_string(kMaxTextBranching));
  }
  if (header.levels < 1 || header.levels > kMaxTextLevels) {
    fail_at(path, 1,
            "levels L = " + std::to_string(header.levels) + " is out of range 1.." + std::to_string(kMaxTextLevels));
  }
  if (header.scoring < 0 || header.scoring > kMaxScoring) {
    fail_at(path, 1,
            "scoring " + std::to_string(header.scoring) + " is not a DBoW2 scoring type (0.." +
                std::to_string(kMaxScoring) + ")");
  }
  if (header.weighting < 0 || header.weighting > kMaxWeighting) {
    fail_at(path, 1,
            "weighting " + std::to_string(header.weighting) + " is not a DBoW2 weighting type (0.." +
                std::to_string(kMaxWeighting) + ")");
  }
  return header;
}

Vocabulary::NodeRecord parse_text_node(const fs::path& path, std::size_t line_number, std::string_view line, NodeId id,
                                       const std::vector<std::uint8_t>& is_leaf_so_far) {
  FieldReader fields(line);
  std::string_view field;
  int field_count = 0;
  auto next_field = [&](const char* what) {
    if (!fields.next(field)) {
      fail_at(path, line_number,
              "node line has " + std::to_string(field_count) +
                  " fields, expected 35 (parent is_leaf d0..d31 weight); missing " + what);
    }
    ++field_count;
  };
  Vocabulary::NodeRecord record;
  std::uint64_t parent = 0;
  next_field("parent");
  if (!parse_number(field, parent))
    fail_at(path, line_number, "parent " + quoted(field) + " is not a non-negative integer");
  if (parent >= id) {
    fail_at(path, line_number,
            "parent " + std::to_string(parent) + " of node " + std::to_string(id) + " is not an earlier node");
  }
  if (is_leaf_so_far[parent]) fail_at(path, line_number, "parent " + std::to_string(parent) + " is a leaf");
  record.parent = static_cast<NodeId>(parent);
  int is_leaf = 0;
  next_field("is_leaf");
  if (!parse_number(field, is_leaf) || (is_leaf != 0 && is_leaf != 1))
    fail_at(path, line_number, "is_leaf " + quoted(field) + " is not 0 or 1");
  record.is_leaf = is_leaf == 1;
  for (std::size_t b = 0; b < record.descriptor.size(); ++b) {
    next_field("descriptor bytes");
    unsigned value = 0;
    if (!parse_number(field, value) || value > 255) {
      fail_at(path, line_number,
              "descriptor byte " + std::to_string(b) + " " + quoted(field) + " is not an integer 0..255");
    }
    record.descriptor[b] = static_cast<std::uint8_t>(value);
  }
  next_field("weight");
  if (!parse_number(field, record.weight) || !std::isfinite(record.weight)) {
    fail_at(path, line_number, "weight " + quoted(field) + " is not a finite number");
  }
  if (fields.next(field)) fail_at(path, line_number, "node line has more than 35 fields (extra " + quoted(field) + ")");
  return record;
}

// --- binary ----------------------------------------------------------------------------------

template <typename T>
void put(std::vector<char>& out, const T& value) {
  const char* bytes = reinterpret_cast<const char*>(&value);
  out.insert(out.end(), bytes, bytes + sizeof(T));
}

template <typename T>
T get(const char* data) {
  T value;
  std::memcpy(&value, data, sizeof(T));
  return value;
}

}  // namespace

std::uint64_t vocabulary_checksum(std::span<const char> bytes) {
  // FNV-1a 64 over little-endian 64-bit words (then the tail byte by byte): byte-wise FNV-1a on a
  // 45 MB file takes ~4 cycles per byte, the word-wise form an eighth of that. Every step is a
  // bijection of the state, so any change to a single word is always detected.
  constexpr std::uint64_t kOffset = 0xcbf29ce484222325ull;
  constexpr std::uint64_t kPrime = 0x100000001b3ull;
  std::uint64_t hash = kOffset;
  std::size_t i = 0;
  for (; i + 8 <= bytes.size(); i += 8) {
    hash ^= get<std::uint64_t>(bytes.data() + i);
    hash *= kPrime;
  }
  for (; i < bytes.size(); ++i) {
    hash ^= static_cast<std::uint8_t>(bytes[i]);
    hash *= kPrime;
  }
  return hash;
}

VocabularyFileFormat detect_vocabulary_format(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open file");
  std::array<char, kBinaryMagic.size()> head{};
  in.read(head.data(), head.size());
  if (in.gcount() == static_cast<std::streamsize>(head.size()) && head == kBinaryMagic)
    return VocabularyFileFormat::kHeslamBinary;
  return VocabularyFileFormat::kDbow2Text;
}

Vocabulary load_vocabulary(const fs::path& path) {
  return detect_vocabulary_format(path) == VocabularyFileFormat::kHeslamBinary ? load_vocabulary_binary(path)
                                                                               : load_vocabulary_text(path);
}

Vocabulary load_vocabulary_text(const fs::path& path) {
  const std::vector<char> data = read_whole_file(path);
  const std::string_view text(data.data(), data.size());
  std::size_t pos = 0;
  std::size_t line_number = 0;
  auto next_line = [&](std::string_view& line) {
    if (pos >= text.size()) return false;
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    return true;
  };

  std::string_view line;
  if (!next_line(line)) fail_at(path, 1, "empty file, expected header 'k L scoring weighting'");
  const TextHeader header = parse_text_header(path, line);

  std::vector<Vocabulary::NodeRecord> nodes;
  std::vector<std::uint8_t> is_leaf{0};  // per node id, root first
  std::vector<std::uint8_t> has_children{0};
  std::vector<std::size_t> line_of_node{1};  // the root's "line" is the header
  while (next_line(line)) {
    if (line.find_first_not_of(" \t\r") == std::string_view::npos) {
      // DBoW2 ends the file with a newline; tolerate blank lines only at the very end.
      if (text.find_first_not_of(" \t\r\n", pos) == std::string_view::npos) break;
      fail_at(path, line_number, "empty line inside the node list");
    }
    const NodeId id = static_cast<NodeId>(nodes.size() + 1);
    nodes.push_back(parse_text_node(path, line_number, line, id, is_leaf));
    is_leaf.push_back(nodes.back().is_leaf ? 1 : 0);
    has_children.push_back(0);
    has_children[nodes.back().parent] = 1;
    line_of_node.push_back(line_number);
  }
  if (nodes.empty()) fail_at(path, line_number + 1, "no nodes after the header (file truncated?)");
  for (std::size_t id = 0; id < is_leaf.size(); ++id) {
    if (!is_leaf[id] && !has_children[id]) {
      fail_at(path, line_of_node[id],
              "node " + std::to_string(id) + " is an inner node without children (file truncated?)");
    }
  }
  try {
    return Vocabulary(header.branching, header.levels, static_cast<BowScoring>(header.scoring),
                      static_cast<BowWeighting>(header.weighting), nodes);
  } catch (const std::invalid_argument& e) {
    fail(path, e.what());
  }
}

void save_vocabulary_text(const fs::path& path, const Vocabulary& vocabulary) {
  const std::vector<Vocabulary::NodeRecord> nodes = vocabulary.node_records();
  // DBoW2's header spelling, two spaces before the scoring included.
  std::string text = std::to_string(vocabulary.branching()) + ' ' + std::to_string(vocabulary.levels()) + "  " +
                     std::to_string(static_cast<int>(vocabulary.scoring())) + ' ' +
                     std::to_string(static_cast<int>(vocabulary.weighting())) + '\n';
  text.reserve(text.size() + nodes.size() * kTextBytesPerNode);
  char number[32];
  auto append = [&](auto value) {
    // Shortest form that reads back to the same value (floats round-trip exactly).
    const auto [end, ec] = std::to_chars(number, number + sizeof(number), value);
    text.append(number, end);
  };
  for (const Vocabulary::NodeRecord& node : nodes) {
    append(node.parent);
    text += node.is_leaf ? " 1" : " 0";
    for (const std::uint8_t byte : node.descriptor) {
      text += ' ';
      append(static_cast<unsigned>(byte));
    }
    text += ' ';
    append(node.weight);
    text += '\n';
  }
  write_atomically(path, text);
}

Vocabulary load_vocabulary_binary(const fs::path& path) {
  const MappedFile file(path);
  const std::span<const char> data = file.bytes();
  if (data.size() < kBinaryHeaderBytes + kChecksumBytes) {
    fail(path, "truncated: " + std::to_string(data.size()) + " bytes, a binary vocabulary has at least " +
                   std::to_string(kBinaryHeaderBytes + kChecksumBytes));
  }
  if (!std::equal(kBinaryMagic.begin(), kBinaryMagic.end(), data.begin()))
    fail(path, "not a heslam binary vocabulary (bad magic)");
  const char* p = data.data() + kBinaryMagic.size();
  const auto version = get<std::uint32_t>(p);
  const auto branching = get<std::uint32_t>(p + 4);
  const auto levels = get<std::uint32_t>(p + 8);
  const auto scoring = get<std::uint32_t>(p + 12);
  const auto weighting = get<std::uint32_t>(p + 16);
  const auto node_count = get<std::uint64_t>(p + 24);
  if (version != kVocabularyBinaryFormatVersion) {
    fail(path, "format version " + std::to_string(version) + ", this build reads version " +
                   std::to_string(kVocabularyBinaryFormatVersion));
  }
  // Checked before the size arithmetic so a corrupt count cannot overflow it.
  const std::size_t max_nodes = (data.size() - kBinaryHeaderBytes - kChecksumBytes) / kBinaryBytesPerNode;
  const std::size_t expected_size =
      kBinaryHeaderBytes + std::min<std::uint64_t>(node_count, max_nodes + 1) * kBinaryBytesPerNode + kChecksumBytes;
  if (node_count > max_nodes || expected_size != data.size()) {
    fail(path, "size " + std::to_string(data.size()) + " bytes does not match the header's " +
                   std::to_string(node_count) + " nodes (" + (node_count > max_nodes ? "truncated" : "trailing bytes") +
                   ")");
  }
  const std::size_t body_size = data.size() - kChecksumBytes;
  const auto stored_checksum = get<std::uint64_t>(data.data() + body_size);
  if (vocabulary_checksum(data.first(body_size)) != stored_checksum) fail(path, "checksum mismatch (file corrupted)");
  if (scoring > static_cast<std::uint32_t>(kMaxScoring) || weighting > static_cast<std::uint32_t>(kMaxWeighting)) {
    fail(path, "unknown scoring " + std::to_string(scoring) + " or weighting " + std::to_string(weighting));
  }

  const std::size_t n = node_count;
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(data.data());
  Vocabulary::NodeColumns columns;
  columns.parents = {bytes + kBinaryHeaderBytes, 4 * n};
  columns.is_leaf = {columns.parents.data() + columns.parents.size(), n};
  columns.descriptors = {columns.is_leaf.data() + n, 32 * n};
  columns.weights = {columns.descriptors.data() + columns.descriptors.size(), 4 * n};
  try {
    return Vocabulary::from_columns(static_cast<int>(branching), static_cast<int>(levels),
                                    static_cast<BowScoring>(scoring), static_cast<BowWeighting>(weighting), columns);
  } catch (const std::invalid_argument& e) {
    fail(path, e.what());
  }
}

void save_vocabulary_binary(const fs::path& path, const Vocabulary& vocabulary) {
  const std::vector<Vocabulary::NodeRecord> nodes = vocabulary.node_records();
  const std::size_t n = nodes.size();
  std::vector<char> data;
  data.reserve(kBinaryHeaderBytes + n * kBinaryBytesPerNode + kChecksumBytes);
  data.insert(data.end(), kBinaryMagic.begin(), kBinaryMagic.end());
  put(data, kVocabularyBinaryFormatVersion);
  put(data, static_cast<std::uint32_t>(vocabulary.branching()));
  put(data, static_cast<std::uint32_t>(vocabulary.levels()));
  put(data, static_cast<std::uint32_t>(vocabulary.scoring()));
  put(data, static_cast<std::uint32_t>(vocabulary.weighting()));
  put(data, std::uint32_t{0});
  put(data, static_cast<std::uint64_t>(n));
  for (const auto& node : nodes) put(data, static_cast<std::uint32_t>(node.parent));
  for (const auto& node : nodes) data.push_back(node.is_leaf ? 1 : 0);
  for (const auto& node : nodes) data.insert(data.end(), node.descriptor.begin(), node.descriptor.end());
  for (const auto& node : nodes) put(data, node.weight);
  put(data, vocabulary_checksum(data));
  write_atomically(path, std::string_view(data.data(), data.size()));
}

}  // namespace heslam
