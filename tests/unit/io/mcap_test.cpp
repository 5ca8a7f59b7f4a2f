// MCAP (io/mcap.hpp) against the specification: what the writer puts in, the reader gets back in
// order, across many chunks; the summary's statistics count what was written; a byte flipped in
// a chunk or the data section is a CRC error naming the field; the layout's fixed points (magic
// at both ends, the footer's offsets) are checked on the raw bytes. The official reader
// (@mcap/core) reads a recorded run in the integration test Recording.*. reserveEnd is tried on
// a file that cannot grow past a size limit (RLIMIT_FSIZE with SIGXFSZ ignored), as a full disk.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/mcap.hpp"
#include "support/file_size_limit.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;

std::vector<unsigned char> bytesOf(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(bytes.size()));
}

std::uint64_t u64At(const std::vector<unsigned char>& b, std::size_t at) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | b[at + static_cast<std::size_t>(i)];
  return v;
}

TEST(Crc32, IsZlibsCrc32) {
  // The check value of CRC-32/ISO-HDLC: crc32("123456789") = 0xCBF43926.
  const std::string text = "123456789";
  EXPECT_EQ(crc32(std::as_bytes(std::span(text.data(), text.size()))), 0xCBF43926U);
  // Continuing from a prefix's CRC gives the whole's.
  const auto all = std::as_bytes(std::span(text.data(), text.size()));
  EXPECT_EQ(crc32(all.subspan(4), crc32(all.first(4))), 0xCBF43926U);
}

struct Written {
  std::uint16_t channel;
  std::uint64_t log_ns, publish_ns;
  std::vector<std::byte> data;
};

TEST(Mcap, WhatIsWrittenIsReadBackInOrderAcrossChunksWithItsSummary) {
  const sensornet::testing::ScratchDir dir;
  const fs::path path = dir.file("round.mcap");
  std::mt19937_64 rng(20261202);
  std::vector<Written> written;
  {
    McapWriter out(path, "sensornet", 512);  // small chunks: many of them
    const auto idl = out.addSchema("sensornet::Measurement", "omgidl", "module sensornet {};");
    const auto a = out.addChannel(idl, "sensornet/Measurement", "cdr", {{"partition", "p/1"}});
    const auto b = out.addChannel(idl, "sensornet/Report", "cdr");
    for (int i = 0; i < 400; ++i) {
      Written w{i % 3 == 0 ? b : a, 1'000'000'000ULL + 1000ULL * static_cast<std::uint64_t>(i),
                static_cast<std::uint64_t>(i), {}};
      w.data.resize(rng() % 40);
      for (std::byte& x : w.data) x = static_cast<std::byte>(rng());
      out.write(w.channel, w.log_ns, w.publish_ns, w.data);
      written.push_back(std::move(w));
    }
    out.addMetadata("run", {{"run_id", "r-1"}, {"seed", "7"}});
    EXPECT_EQ(out.messageCount(), 400u);
  }  // the destructor closes it
  const McapReader in(path);
  EXPECT_EQ(in.profile(), "sensornet");
  ASSERT_EQ(in.schemas().size(), 1u);
  EXPECT_EQ(in.schemas().at(1).encoding, "omgidl");
  ASSERT_EQ(in.channels().size(), 2u);
  EXPECT_EQ(in.channels().at(0).metadata.at("partition"), "p/1");
  EXPECT_EQ(in.channels().at(1).topic, "sensornet/Report");
  ASSERT_EQ(in.messages().size(), written.size());
  std::vector<std::uint32_t> sequence(2, 0);
  std::uint64_t per_channel[2] = {0, 0};
  for (std::size_t i = 0; i < written.size(); ++i) {
    const McapMessage& m = in.messages()[i];
    EXPECT_EQ(m.channel_id, written[i].channel);
    EXPECT_EQ(m.log_time_ns, written[i].log_ns);
    EXPECT_EQ(m.publish_time_ns, written[i].publish_ns);
    EXPECT_EQ(m.data, written[i].data) << "message " << i;
    EXPECT_EQ(m.sequence, sequence[m.channel_id]++) << "per-channel sequence";
    ++per_channel[m.channel_id];
  }
  EXPECT_GT(in.chunkCount(), 10u);
  ASSERT_TRUE(in.statistics().has_value());
  const McapStatistics& s = *in.statistics();
  EXPECT_EQ(s.message_count, 400u);
  EXPECT_EQ(s.channel_count, 2u);
  EXPECT_EQ(s.schema_count, 1u);
  EXPECT_EQ(s.metadata_count, 1u);
  EXPECT_EQ(s.chunk_count, in.chunkCount());
  EXPECT_EQ(s.message_start_ns, written.front().log_ns);
  EXPECT_EQ(s.message_end_ns, written.back().log_ns);
  EXPECT_EQ(s.channel_message_counts.at(0), per_channel[0]);
  EXPECT_EQ(s.channel_message_counts.at(1), per_channel[1]);
  ASSERT_EQ(in.metadata().size(), 1u);
  EXPECT_EQ(in.metadata()[0].second.at("seed"), "7");

  // The fixed points: magic at both ends; the footer (opcode 0x02, length 20) names where the
  // summary and the summary offsets start, each at a record of the right opcode.
  const auto bytes = bytesOf(path);
  const unsigned char magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  EXPECT_EQ(std::memcmp(bytes.data(), magic, 8), 0);
  EXPECT_EQ(std::memcmp(bytes.data() + bytes.size() - 8, magic, 8), 0);
  const std::size_t footer = bytes.size() - 8 - (1 + 8 + 20);
  EXPECT_EQ(bytes[footer], 0x02);
  EXPECT_EQ(u64At(bytes, footer + 1), 20u);
  const std::uint64_t summary = u64At(bytes, footer + 9);
  const std::uint64_t offsets = u64At(bytes, footer + 17);
  EXPECT_EQ(bytes[summary], 0x03) << "the summary begins with the schemas";
  EXPECT_EQ(bytes[offsets], 0x0E) << "then summary offset records";
  EXPECT_EQ(bytes[summary - 13], 0x0F) << "the data section ends with Data End";
}

TEST(Mcap, ADamagedFileIsRefusedNamingWhatIsWrong) {
  const sensornet::testing::ScratchDir dir;
  const fs::path path = dir.file("damaged.mcap");
  {
    McapWriter out(path, "sensornet");
    const auto schema = out.addSchema("s", "omgidl", "x");
    const auto channel = out.addChannel(schema, "t", "cdr");
    const std::vector<std::byte> payload(64, std::byte{7});
    for (int i = 0; i < 10; ++i) out.write(channel, 10 + i, 0, payload);
    out.close();
  }
  auto bytes = bytesOf(path);
  const auto expectRefused = [&](const std::vector<unsigned char>& damaged, const std::string& field) {
    const fs::path bad = dir.file("bad.mcap");
    writeBytes(bad, damaged);
    try {
      (void)McapReader(bad);
      FAIL() << "a damaged file was read (" << field << ")";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  auto flipped = bytes;
  flipped[200] ^= 0x01;  // inside the chunk's records
  expectRefused(flipped, "chunk");
  auto truncated = bytes;
  truncated.resize(bytes.size() / 2);  // an interrupted copy
  expectRefused(truncated, "record");
  auto not_mcap = bytes;
  not_mcap[1] = 'X';
  expectRefused(not_mcap, "magic");
}

using sensornet::testing::FileSizeLimit;

// The same content every time: a schema, two channels, 300 messages over many chunks.
void writeSome(McapWriter& out) {
  const auto idl = out.addSchema("sensornet::Measurement", "omgidl", std::string(900, 'i'));
  const auto a = out.addChannel(idl, "sensornet/Measurement", "cdr", {{"partition", "p/1"}});
  const auto b = out.addChannel(idl, "sensornet/Report", "cdr");
  for (int i = 0; i < 300; ++i) {
    const std::vector<std::byte> data(static_cast<std::size_t>(i % 37), std::byte{0x5a});
    out.write(i % 4 == 0 ? b : a, 1000U + static_cast<std::uint64_t>(i), 7, data);
  }
}

// After reserveEnd, close() writes into room already on disk: with the file unable to grow by a
// byte, the metadata, summary and footer still go in, the file reads back whole, and the room
// left over (less than the metadata allowance) is cut off.
TEST(Mcap, AfterReserveEndTheFileClosesWithoutGrowing) {
  const sensornet::testing::ScratchDir dir;
  const fs::path path = dir.file("reserved.mcap");
  constexpr std::size_t kMetadataRoom = 512;
  std::uintmax_t reserved = 0;
  {
    McapWriter out(path, "sensornet", 1024);
    writeSome(out);
    out.reserveEnd(kMetadataRoom);
    reserved = fs::file_size(path);
    const FileSizeLimit limit(reserved);
    out.addMetadata("run-end", {{"status", "completed"}, {"exit_code", "0"}});
    EXPECT_NO_THROW(out.close());
  }
  const std::uintmax_t closed = fs::file_size(path);
  EXPECT_LT(closed, reserved);
  EXPECT_LE(reserved - closed, kMetadataRoom) << "reserveEnd made room for more than close() needs";
  const McapReader in(path);
  EXPECT_EQ(in.messages().size(), 300u);
  ASSERT_EQ(in.metadata().size(), 1u);
  EXPECT_EQ(in.metadata()[0].second.at("status"), "completed");
}

// A disk too full for the file's end: reserveEnd says so, naming the file and why, and the file
// ends where its data ends (a prefix of the same content closed without a limit), not in zeros.
TEST(Mcap, ReserveEndOnAFullDiskNamesTheFileAndLeavesTheDataAsWritten) {
  const sensornet::testing::ScratchDir dir;
  const fs::path whole = dir.file("whole.mcap");
  {
    McapWriter out(whole, "sensornet", 1024);
    writeSome(out);
  }
  const auto complete = bytesOf(whole);
  const fs::path path = dir.file("full.mcap");
  {
    McapWriter out(path, "sensornet", 1024);
    const FileSizeLimit limit(complete.size() - 1);  // the data fits, its end does not
    writeSome(out);
    try {
      out.reserveEnd(0);
      ADD_FAILURE() << "reserveEnd succeeded with no room for the file's end";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(std::strerror(EFBIG)), std::string::npos) << e.what();
    }
  }  // the destructor's close() fails quietly past the limit
  const auto left = bytesOf(path);
  ASSERT_LT(left.size(), complete.size());
  EXPECT_GT(left.size(), 1000u) << "the chunks written before are kept";
  EXPECT_TRUE(std::equal(left.begin(), left.end(), complete.begin()));
}

}  // namespace
}  // namespace sensornet
