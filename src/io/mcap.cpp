#include "sensornet/io/mcap.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

constexpr std::array<unsigned char, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

const std::array<std::uint32_t, 256>& crcTable() {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1U) != 0 ? 0xEDB88320U ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  return table;
}

// Little-endian record fields (the spec's uint8..uint64, String, Bytes, Map, Array).
class Out {
 public:
  Out& u8(std::uint8_t v) { return raw(&v, 1); }
  Out& u16(std::uint16_t v) { return le(v); }
  Out& u32(std::uint32_t v) { return le(v); }
  Out& u64(std::uint64_t v) { return le(v); }
  Out& str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    return raw(s.data(), s.size());
  }
  Out& bytes32(std::span<const std::byte> b) {
    u32(static_cast<std::uint32_t>(b.size()));
    return raw(b.data(), b.size());
  }
  Out& map(const McapMap& m) {
    Out entries;
    for (const auto& [k, v] : m) entries.str(k).str(v);
    return bytes32(entries.data());
  }
  Out& raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::byte*>(p);
    data_.insert(data_.end(), b, b + n);
    return *this;
  }
  Out& raw(std::span<const std::byte> b) { return raw(b.data(), b.size()); }
  [[nodiscard]] const std::vector<std::byte>& data() const { return data_; }
  [[nodiscard]] std::size_t size() const { return data_.size(); }

 private:
  template <class V>
  Out& le(V v) {
    std::array<std::byte, sizeof(V)> b{};
    for (std::size_t i = 0; i < sizeof(V); ++i) b[i] = static_cast<std::byte>((v >> (8 * i)) & 0xFF);
    return raw(b.data(), b.size());
  }
  std::vector<std::byte> data_;
};

std::vector<std::byte> record(std::uint8_t op, const Out& content) {
  Out r;
  r.u8(op).u64(content.size()).raw(content.data());
  return r.data();
}

// Reads record fields; every read past the end is an InputError naming the file.
class In {
 public:
  In(std::span<const std::byte> data, const std::string& source) : data_(data), source_(source) {}
  std::uint8_t u8() { return static_cast<std::uint8_t>(take(1)[0]); }
  std::uint16_t u16() { return le<std::uint16_t>(); }
  std::uint32_t u32() { return le<std::uint32_t>(); }
  std::uint64_t u64() { return le<std::uint64_t>(); }
  std::string str() {
    const auto b = take(u32());
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  std::span<const std::byte> bytes32() { return take(u32()); }
  std::span<const std::byte> bytes64() { return take(u64()); }
  McapMap map() {
    In entries(bytes32(), source_);
    McapMap m;
    while (!entries.done()) {
      std::string k = entries.str();
      m[k] = entries.str();
    }
    return m;
  }
  std::span<const std::byte> take(std::uint64_t n) {
    if (n > data_.size() - at_) {
      throw InputError(source_, "record", "a complete record at byte " + std::to_string(at_) +
                                              " (it needs " + std::to_string(n) + " bytes, " +
                                              std::to_string(data_.size() - at_) + " are left)");
    }
    const auto b = data_.subspan(at_, n);
    at_ += n;
    return b;
  }
  [[nodiscard]] std::span<const std::byte> rest() { return take(data_.size() - at_); }
  [[nodiscard]] bool done() const { return at_ == data_.size(); }
  [[nodiscard]] std::size_t position() const { return at_; }

 private:
  template <class V>
  V le() {
    const auto b = take(sizeof(V));
    V v = 0;
    for (std::size_t i = 0; i < sizeof(V); ++i) v |= static_cast<V>(static_cast<V>(b[i]) << (8 * i));
    return v;
  }
  std::span<const std::byte> data_;
  std::string source_;
  std::size_t at_ = 0;
};

}  // namespace

std::uint32_t crc32(std::span<const std::byte> bytes, std::uint32_t crc) {
  const auto& table = crcTable();
  crc = ~crc;
  for (const std::byte b : bytes) crc = table[(crc ^ static_cast<std::uint8_t>(b)) & 0xFFU] ^ (crc >> 8);
  return ~crc;
}

// --- writer --------------------------------------------------------------------------------

struct McapWriter::ChunkIndex {
  std::uint64_t start_ns, end_ns, offset, length;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length, size;
};

McapWriter::McapWriter(const std::filesystem::path& path, const std::string& profile,
                       std::size_t chunk_bytes)
    : path_(path), chunk_bytes_(chunk_bytes) {
  file_ = std::fopen(path.c_str(), "wb");
  if (file_ == nullptr) {
    throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(errno));
  }
  // Unbuffered: every record goes out whole in one call (messages wait in the chunk), so that
  // offset_ is what the file holds and a write that fails is known at once.
  std::setvbuf(file_, nullptr, _IONBF, 0);
  Out magic;
  magic.raw(kMagic.data(), kMagic.size());
  append(magic.data());
  Out header;
  header.str(profile).str("sensornet");
  append(record(kHeader, header));
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (const std::exception&) {
    // A destructor does not throw; close() reports the error to callers that call it.
  }
}

void McapWriter::append(const std::vector<std::byte>& bytes) {
  if (failed_) throw std::runtime_error("cannot write " + path_.string() + " after a failed write");
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    const int error = errno;
    fail();
    errno = error;
    throw std::runtime_error("cannot write " + path_.string() + ": " + std::strerror(errno));
  }
  offset_ += bytes.size();
  data_crc_ = crc32(bytes, data_crc_);
}

std::uint16_t McapWriter::addSchema(const std::string& name, const std::string& encoding,
                                    const std::string& data) {
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);  // 0 means "no schema"
  Out s;
  s.u16(id).str(name).str(encoding).bytes32(std::as_bytes(std::span(data.data(), data.size())));
  schemas_.push_back(record(kSchema, s));
  chunk_.insert(chunk_.end(), schemas_.back().begin(), schemas_.back().end());
  return id;
}

std::uint16_t McapWriter::addChannel(std::uint16_t schema_id, const std::string& topic,
                                     const std::string& message_encoding,
                                     const McapMap& metadata) {
  const auto id = static_cast<std::uint16_t>(channels_.size());
  Out c;
  c.u16(id).u16(schema_id).str(topic).str(message_encoding).map(metadata);
  channels_.push_back(record(kChannel, c));
  chunk_.insert(chunk_.end(), channels_.back().begin(), channels_.back().end());
  channel_counts_[id] = 0;
  return id;
}

void McapWriter::write(std::uint16_t channel_id, std::uint64_t log_time_ns,
                       std::uint64_t publish_time_ns, std::span<const std::byte> data) {
  if (file_ == nullptr) throw std::runtime_error("write to closed " + path_.string());
  Out m;
  m.u16(channel_id).u32(sequences_[channel_id]++).u64(log_time_ns).u64(publish_time_ns).raw(data);
  const auto rec = record(kMessage, m);
  if (chunk_index_.empty()) chunk_start_ns_ = chunk_end_ns_ = log_time_ns;  // its first message
  chunk_index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  chunk_.insert(chunk_.end(), rec.begin(), rec.end());
  chunk_start_ns_ = std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, log_time_ns);
  first_ns_ = message_count_ == 0 ? log_time_ns : std::min(first_ns_, log_time_ns);
  last_ns_ = std::max(last_ns_, log_time_ns);
  ++message_count_;
  ++channel_counts_[channel_id];
  if (chunk_.size() >= chunk_bytes_) flushChunk();
}

void McapWriter::flushChunk() {
  if (chunk_.empty()) return;
  Out c;
  c.u64(chunk_start_ns_).u64(chunk_end_ns_).u64(chunk_.size()).u32(crc32(chunk_)).str("");
  c.u64(chunk_.size()).raw(chunk_);
  ChunkIndex index{chunk_start_ns_, chunk_end_ns_, offset_, 0, {}, 0, chunk_.size()};
  const auto rec = record(kChunk, c);
  append(rec);
  index.length = rec.size();
  const std::uint64_t indexes_start = offset_;
  for (const auto& [channel, entries] : chunk_index_) {
    Out array;
    for (const auto& [time, at] : entries) array.u64(time).u64(at);
    Out mi;
    mi.u16(channel).bytes32(array.data());
    index.message_index_offsets[channel] = offset_;
    append(record(kMessageIndex, mi));
  }
  index.message_index_length = offset_ - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  chunk_.clear();
  chunk_index_.clear();
  chunk_start_ns_ = chunk_end_ns_ = 0;
}

void McapWriter::addMetadata(const std::string& name, const McapMap& metadata) {
  flushChunk();  // metadata records live outside chunks
  Out m;
  m.str(name).map(metadata);
  const std::uint64_t at = offset_;
  const auto rec = record(kMetadata, m);
  append(rec);
  Out index;
  index.u64(at).u64(rec.size()).str(name);
  metadata_indexes_.push_back(record(kMetadataIndex, index));
  ++metadata_count_;
}

// Each record is an opcode and a u64 length before its content (kRecordHead); the sizes below
// follow close()'s records field by field.
std::uint64_t McapWriter::endBytes() const {
  constexpr std::uint64_t kRecordHead = 1 + 8;
  constexpr std::uint64_t kGroups = 6;  // schemas, channels, statistics, chunk and metadata indexes
  std::uint64_t bytes = kRecordHead + 4;  // Data End
  for (const auto& r : schemas_) bytes += r.size();
  for (const auto& r : channels_) bytes += r.size();
  bytes += kRecordHead + 8 + 2 + 4 + 4 + 4 + 4 + 8 + 8 + 4 + 10 * channel_counts_.size();
  for (const ChunkIndex& i : chunk_indexes_) {
    bytes += kRecordHead + 4 * 8 + 4 + 10 * i.message_index_offsets.size() + 8 + 4 + 8 + 8;
  }
  for (const auto& r : metadata_indexes_) bytes += r.size();
  bytes += kGroups * (kRecordHead + 1 + 8 + 8);  // summary offsets
  bytes += kRecordHead + 8 + 8 + 4 + kMagic.size();  // footer and the closing magic
  return bytes;
}

// A write failed: the file is cut back to its last whole record, and nothing more goes in.
void McapWriter::fail() {
  failed_ = true;
  (void)::ftruncate(::fileno(file_), static_cast<off_t>(offset_));
}

void McapWriter::reserveEnd(std::size_t metadata_bytes) {
  if (file_ == nullptr) throw std::runtime_error("write to closed " + path_.string());
  flushChunk();
  if (std::fflush(file_) != 0) {
    const std::string why = std::strerror(errno);
    fail();
    throw std::runtime_error("cannot write " + path_.string() + ": " + why);
  }
  // Past the buffered stream: its position stays at offset_, where close() goes on.
  const int fd = ::fileno(file_);
  const std::vector<std::byte> zeros(endBytes() + metadata_bytes);
  std::size_t done = 0;
  while (done < zeros.size()) {
    const ssize_t n = ::pwrite(fd, zeros.data() + done, zeros.size() - done,
                               static_cast<off_t>(offset_ + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n < 0 ? std::strerror(errno) : "no room";
      fail();
      throw std::runtime_error("cannot write " + path_.string() + ": " + why);
    }
    done += static_cast<std::size_t>(n);
  }
  reserved_to_ = offset_ + zeros.size();
}

void McapWriter::close() {
  if (file_ == nullptr) return;
  if (failed_) {  // fail() cut the file back to its last whole record: nothing more goes in
    (void)std::fclose(file_);
    file_ = nullptr;
    return;
  }
  flushChunk();
  Out end;
  end.u32(data_crc_);
  append(record(kDataEnd, end));

  // The summary section, one group per record kind, and where each group starts.
  const std::uint64_t summary_start = offset_;
  std::uint32_t summary_crc = 0;
  std::vector<std::tuple<std::uint8_t, std::uint64_t, std::uint64_t>> groups;
  const auto group = [&](std::uint8_t op, const std::vector<std::vector<std::byte>>& records) {
    if (records.empty()) return;
    const std::uint64_t start = offset_;
    for (const auto& r : records) {
      append(r);
      summary_crc = crc32(r, summary_crc);
    }
    groups.emplace_back(op, start, offset_ - start);
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  Out stats;
  stats.u64(message_count_).u16(static_cast<std::uint16_t>(schemas_.size()));
  stats.u32(static_cast<std::uint32_t>(channels_.size())).u32(0).u32(metadata_count_);
  stats.u32(static_cast<std::uint32_t>(chunk_indexes_.size())).u64(first_ns_).u64(last_ns_);
  Out counts;
  for (const auto& [channel, count] : channel_counts_) counts.u16(channel).u64(count);
  stats.bytes32(counts.data());
  group(kStatistics, {record(kStatistics, stats)});
  std::vector<std::vector<std::byte>> chunk_records;
  for (const ChunkIndex& i : chunk_indexes_) {
    Out c;
    c.u64(i.start_ns).u64(i.end_ns).u64(i.offset).u64(i.length);
    Out offsets;
    for (const auto& [channel, at] : i.message_index_offsets) offsets.u16(channel).u64(at);
    c.bytes32(offsets.data()).u64(i.message_index_length).str("").u64(i.size).u64(i.size);
    chunk_records.push_back(record(kChunkIndex, c));
  }
  group(kChunkIndex, chunk_records);
  group(kMetadataIndex, metadata_indexes_);

  const std::uint64_t offsets_start = offset_;
  for (const auto& [op, start, length] : groups) {
    Out o;
    o.u8(op).u64(start).u64(length);
    const auto r = record(kSummaryOffset, o);
    append(r);
    summary_crc = crc32(r, summary_crc);
  }
  Out footer_head;  // the footer up to its CRC, which covers it too
  footer_head.u8(kFooter).u64(8 + 8 + 4).u64(summary_start).u64(offsets_start);
  summary_crc = crc32(footer_head.data(), summary_crc);
  Out footer;
  footer.raw(footer_head.data()).u32(summary_crc).raw(kMagic.data(), kMagic.size());
  append(footer.data());
  std::FILE* file = file_;
  file_ = nullptr;
  // What reserveEnd made room for and close() did not need goes.
  const bool cut = reserved_to_ <= offset_ ||
                   (std::fflush(file) == 0 && ::ftruncate(::fileno(file), static_cast<off_t>(offset_)) == 0);
  if (std::fclose(file) != 0 || !cut) {
    throw std::runtime_error("cannot write " + path_.string() + ": " + std::strerror(errno));
  }
}

// --- reader --------------------------------------------------------------------------------

namespace {

// Calls on_record(opcode, content) for each record; at the top level, up to the Footer.
void readRecords(In& in, const std::string& source,
                 const std::function<void(std::uint8_t, In&)>& on_record, bool top_level) {
  while (!in.done()) {
    const std::uint8_t op = in.u8();
    In content(in.take(in.u64()), source);
    on_record(op, content);
    if (top_level && op == kFooter) return;
  }
}

}  // namespace

McapReader::McapReader(const std::filesystem::path& path) {
  const std::string source = path.string();
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(source, "file", "a readable MCAP file");
  const std::vector<char> text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const auto bytes = std::as_bytes(std::span(text.data(), text.size()));
  if (bytes.size() < 2 * kMagic.size() ||
      std::memcmp(bytes.data(), kMagic.data(), kMagic.size()) != 0) {
    throw InputError(source, "magic", "an MCAP file (it starts with \\x89MCAP0\\r\\n)");
  }
  In in(bytes.subspan(kMagic.size()), source);
  bool footer = false;
  const auto onMessage = [&](In& c) {
    McapMessage m;
    m.channel_id = c.u16();
    m.sequence = c.u32();
    m.log_time_ns = c.u64();
    m.publish_time_ns = c.u64();
    const auto data = c.rest();
    m.data.assign(data.begin(), data.end());
    if (!channels_.contains(m.channel_id)) {
      throw InputError(source, "message.channel_id",
                       "a channel defined before its messages, got " + std::to_string(m.channel_id));
    }
    messages_.push_back(std::move(m));
  };
  const auto onSchema = [&](In& c) {
    McapSchema s;
    s.id = c.u16();
    s.name = c.str();
    s.encoding = c.str();
    const auto data = c.bytes32();
    s.data.assign(reinterpret_cast<const char*>(data.data()), data.size());
    schemas_[s.id] = s;
  };
  const auto onChannel = [&](In& c) {
    McapChannel ch;
    ch.id = c.u16();
    ch.schema_id = c.u16();
    ch.topic = c.str();
    ch.message_encoding = c.str();
    ch.metadata = c.map();
    channels_[ch.id] = ch;
  };
  std::size_t data_end_at = 0;
  readRecords(
      in, source,
      [&](std::uint8_t op, In& c) {
        switch (op) {
          case kHeader:
            profile_ = c.str();
            break;
          case kSchema: onSchema(c); break;
          case kChannel: onChannel(c); break;
          case kMessage: onMessage(c); break;
          case kChunk: {
            (void)c.u64();
            (void)c.u64();
            const std::uint64_t size = c.u64();
            const std::uint32_t crc = c.u32();
            const std::string compression = c.str();
            if (!compression.empty()) {
              throw InputError(source, "chunk.compression",
                               "uncompressed chunks (this reader has no '" + compression + "')");
            }
            const auto records = c.bytes64();
            if (records.size() != size || (crc != 0 && crc32(records) != crc)) {
              throw InputError(source, "chunk", "records of the stated size and CRC-32");
            }
            ++chunk_count_;
            In inner(records, source);
            readRecords(inner, source, [&](std::uint8_t inner_op, In& r) {
              if (inner_op == kSchema) onSchema(r);
              if (inner_op == kChannel) onChannel(r);
              if (inner_op == kMessage) onMessage(r);
            }, false);
            break;
          }
          case kMetadata: {
            std::string name = c.str();
            metadata_.emplace_back(std::move(name), c.map());
            break;
          }
          case kStatistics: {
            McapStatistics s;
            s.message_count = c.u64();
            s.schema_count = c.u16();
            s.channel_count = c.u32();
            s.attachment_count = c.u32();
            s.metadata_count = c.u32();
            s.chunk_count = c.u32();
            s.message_start_ns = c.u64();
            s.message_end_ns = c.u64();
            In counts(c.bytes32(), source);
            while (!counts.done()) {
              const std::uint16_t channel = counts.u16();
              s.channel_message_counts[channel] = counts.u64();
            }
            statistics_ = s;
            break;
          }
          case kDataEnd: {
            const std::uint32_t crc = c.u32();
            data_end_at = kMagic.size() + in.position() - (1 + 8 + 4);
            if (crc != 0 && crc32(bytes.first(data_end_at)) != crc) {
              throw InputError(source, "data_end.data_section_crc",
                               "the CRC-32 of the data section (the file is damaged)");
            }
            break;
          }
          case kFooter: footer = true; break;
          default: break;  // indexes and records this reader does not need
        }
      },
      true);
  if (!footer) throw InputError(source, "footer", "a complete file (it has no footer)");
}

}  // namespace sensornet
