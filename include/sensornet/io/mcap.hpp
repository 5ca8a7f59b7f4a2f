#pragma once
// MCAP files (https://mcap.dev/spec, format version 0), written and read here from the
// specification; Debian packages no MCAP library.
//
//   McapWriter out("run.mcap", "sensornet");           // magic and header written
//   const auto schema = out.addSchema("sensornet::Measurement", "omgidl", idl_text);
//   const auto channel = out.addChannel(schema, "sensornet/Measurement", "cdr", {{"k", "v"}});
//   out.write(channel, log_ns, publish_ns, cdr_bytes);  // into the open chunk
//   out.addMetadata("run", {{"run_id", "r1"}});
//   out.close();                                         // last chunk, summary, footer
//
// The layout: magic, Header, then the data section (Schema and Channel records, Chunks of
// messages each followed by its Message Index records, Metadata), Data End with the data
// section's CRC-32; then the summary section (every Schema and Channel again, Statistics, a
// Chunk Index per chunk, a Metadata Index per metadata record), the Summary Offset records, and
// the Footer with the summary's CRC-32; magic. Chunks are uncompressed (compression ""), closed
// at about `chunk_bytes` of records. A writer that is destroyed without close() still closes the
// file properly (an interrupted recording stays readable); a write error throws
// std::runtime_error naming the file.
//
// McapReader reads such a file (any MCAP with uncompressed chunks, or messages outside chunks):
// its summary when there is one, and every message in file order.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace sensornet {

using McapMap = std::map<std::string, std::string>;

class McapWriter {
 public:
  McapWriter(const std::filesystem::path& path, const std::string& profile,
             std::size_t chunk_bytes = 1 << 20);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  std::uint16_t addSchema(const std::string& name, const std::string& encoding,
                          const std::string& data);
  std::uint16_t addChannel(std::uint16_t schema_id, const std::string& topic,
                           const std::string& message_encoding, const McapMap& metadata = {});
  void write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
             std::span<const std::byte> data);
  void addMetadata(const std::string& name, const McapMap& metadata);
  // Writes the open chunk and makes room on disk for everything close() will write: the
  // summary, the footer, and `metadata_bytes` of metadata records (with their index entries)
  // added before it. After it, close() needs no new space, so a disk that is full shows here,
  // while the caller can still count it, and not in a file that never gets its end. The room is
  // zeros past the data that close() overwrites and cuts off after the footer. Throws what
  // cannot be written; the file then ends after its last whole record.
  void reserveEnd(std::size_t metadata_bytes);
  // Writes the last chunk, the summary and the footer; the file is complete after it. Idempotent.
  // After a failed write it only closes the file, which then ends after its last whole record.
  void close();

  [[nodiscard]] std::uint64_t messageCount() const { return message_count_; }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  struct ChunkIndex;
  void flushChunk();
  void append(const std::vector<std::byte>& bytes);
  void fail();
  [[nodiscard]] std::uint64_t endBytes() const;  // what close() writes past the open chunk, at most

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::size_t chunk_bytes_;
  std::uint64_t offset_ = 0;       // bytes written so far
  std::uint32_t data_crc_ = 0;     // running CRC-32 of the data section (magic included)
  std::vector<std::vector<std::byte>> schemas_, channels_;  // their records, for the summary
  std::vector<std::byte> chunk_;   // the open chunk's records
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;
  std::uint64_t chunk_start_ns_ = 0, chunk_end_ns_ = 0;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<std::vector<std::byte>> metadata_indexes_;
  std::map<std::uint16_t, std::uint64_t> channel_counts_;
  std::map<std::uint16_t, std::uint32_t> sequences_;
  std::uint64_t message_count_ = 0, first_ns_ = 0, last_ns_ = 0;
  std::uint32_t metadata_count_ = 0;
  std::uint64_t reserved_to_ = 0;  // reserveEnd: the file's size with the room made
  bool failed_ = false;            // a write failed: close() adds nothing
};

struct McapSchema {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};

struct McapChannel {
  std::uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
  McapMap metadata;
};

struct McapMessage {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0, publish_time_ns = 0;
  std::vector<std::byte> data;
};

struct McapStatistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0, attachment_count = 0, metadata_count = 0, chunk_count = 0;
  std::uint64_t message_start_ns = 0, message_end_ns = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

class McapReader {
 public:
  // Reads the whole file; throws InputError naming the file and what is wrong (bad magic, a
  // record that runs past the end, a CRC that does not match, a compressed chunk).
  explicit McapReader(const std::filesystem::path& path);

  [[nodiscard]] const std::string& profile() const { return profile_; }
  [[nodiscard]] const std::map<std::uint16_t, McapSchema>& schemas() const { return schemas_; }
  [[nodiscard]] const std::map<std::uint16_t, McapChannel>& channels() const { return channels_; }
  [[nodiscard]] const std::vector<std::pair<std::string, McapMap>>& metadata() const {
    return metadata_;
  }
  // The summary's Statistics record, if the file has a summary.
  [[nodiscard]] const std::optional<McapStatistics>& statistics() const { return statistics_; }
  [[nodiscard]] std::uint32_t chunkCount() const { return chunk_count_; }
  // Every message, in file order.
  [[nodiscard]] const std::vector<McapMessage>& messages() const { return messages_; }

 private:
  std::string profile_;
  std::map<std::uint16_t, McapSchema> schemas_;
  std::map<std::uint16_t, McapChannel> channels_;
  std::vector<std::pair<std::string, McapMap>> metadata_;
  std::optional<McapStatistics> statistics_;
  std::uint32_t chunk_count_ = 0;
  std::vector<McapMessage> messages_;
};

// CRC-32 (ISO-HDLC, as zlib's crc32) of `bytes`, continuing from `crc`.
[[nodiscard]] std::uint32_t crc32(std::span<const std::byte> bytes, std::uint32_t crc = 0);

}  // namespace sensornet
