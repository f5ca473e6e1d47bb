#include "crunch/io/recording.h"

#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <cstring>

namespace crunch::io {

namespace {

constexpr char kMagic[8] = {'C', 'R', 'U', 'N', 'C', 'H', 'R', 'C'};
constexpr std::size_t kMaxMetadata = 1 << 20;  // 1 MiB: a header claiming more is damaged
constexpr std::size_t kWriterBuffer = 256 * 1024;

constexpr std::array<std::uint32_t, 256> makeCrcTable() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = makeCrcTable();

void put16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint16_t get16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t get32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
std::uint64_t get64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::uint64_t realtimeNs() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

bool validStream(std::uint8_t s) { return s >= 1 && s <= 3; }

}  // namespace

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  crc = ~crc;
  for (const std::uint8_t b : bytes) crc = kCrcTable[(crc ^ b) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

std::uint64_t monotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

std::size_t Chunk::assign(StreamId id, std::uint64_t t, std::span<const std::uint8_t> src) {
  stream = id;
  t_ns = t;
  const std::size_t n = std::min(src.size(), kMaxChunkBytes);
  if (n > 0) std::memcpy(bytes.data(), src.data(), n);  // an empty span's data() may be null
  size = static_cast<std::uint16_t>(n);
  return n;
}

// ---- writer ----

RecordingWriter::RecordingWriter(std::string path, int fd) : path_(std::move(path)), fd_(fd) {
  buffer_.reserve(kWriterBuffer);
}

RecordingWriter::~RecordingWriter() { (void)close(); }

Result<std::unique_ptr<RecordingWriter>> RecordingWriter::create(
    const std::string& path, const std::string& metadata_json) {
  if (metadata_json.size() > kMaxMetadata) {
    return Error{"recording " + path + ": metadata larger than 1 MiB"};
  }
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    return Error{"recording " + path + ": cannot create: " + std::strerror(errno)};
  }
  auto w = std::unique_ptr<RecordingWriter>(new RecordingWriter(path, fd));
  std::uint8_t h[kRecordingHeaderBytes] = {};
  std::memcpy(h, kMagic, 8);
  put16(h + 8, kRecordingVersion);
  put16(h + 10, static_cast<std::uint16_t>(kRecordingHeaderBytes));
  put32(h + 12, static_cast<std::uint32_t>(metadata_json.size()));
  put64(h + 16, realtimeNs());
  put32(h + 24, crc32({reinterpret_cast<const std::uint8_t*>(metadata_json.data()),
                       metadata_json.size()}));
  put32(h + 28, crc32({h, 28}));
  w->buffer_.insert(w->buffer_.end(), h, h + kRecordingHeaderBytes);
  w->buffer_.insert(w->buffer_.end(), metadata_json.begin(), metadata_json.end());
  w->bytes_ = w->buffer_.size();
  if (auto s = w->flush(); !s) return s.error();
  return w;
}

Status RecordingWriter::writeOut() {
  std::size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      buffer_.clear();
      return Error{"recording " + path_ + ": write failed: " + std::strerror(err)};
    }
    done += static_cast<std::size_t>(n);
  }
  buffer_.clear();
  return okStatus();
}

Status RecordingWriter::write(StreamId stream, std::uint64_t t_ns,
                              std::span<const std::uint8_t> bytes) {
  assert(bytes.size() <= kMaxChunkBytes);
  if (fd_ < 0) return Error{"recording " + path_ + ": written after close"};
  const std::size_t total = kRecordHeaderBytes + bytes.size() + 4;
  if (buffer_.size() + total > buffer_.capacity()) {
    if (auto s = writeOut(); !s) return s;
  }
  const std::size_t at = buffer_.size();
  buffer_.resize(at + total);  // within the reserved capacity: no allocation
  std::uint8_t* p = buffer_.data() + at;
  p[0] = static_cast<std::uint8_t>(stream);
  p[1] = 0;
  put16(p + 2, static_cast<std::uint16_t>(bytes.size()));
  put64(p + 4, t_ns);
  if (!bytes.empty()) std::memcpy(p + kRecordHeaderBytes, bytes.data(), bytes.size());
  put32(p + kRecordHeaderBytes + bytes.size(), crc32({p, kRecordHeaderBytes + bytes.size()}));
  ++records_;
  bytes_ += total;
  return okStatus();
}

Status RecordingWriter::mark(MarkKind kind, std::uint64_t t_ns) {
  const std::uint8_t payload = static_cast<std::uint8_t>(kind);
  return write(StreamId::kMark, t_ns, {&payload, 1});
}

Status RecordingWriter::flush() {
  if (fd_ < 0) return okStatus();
  if (auto s = writeOut(); !s) return s;
  if (::fsync(fd_) != 0 && errno != EINVAL) {
    return Error{"recording " + path_ + ": fsync failed: " + std::strerror(errno)};
  }
  return okStatus();
}

Status RecordingWriter::close() {
  if (fd_ < 0) return okStatus();
  Status s = flush();
  ::close(fd_);
  fd_ = -1;
  return s;
}

// ---- reader ----

RecordingReader::RecordingReader(std::string path, std::FILE* file)
    : path_(std::move(path)), file_(file) {}

RecordingReader::~RecordingReader() {
  if (file_ != nullptr) std::fclose(file_);
}

Result<std::unique_ptr<RecordingReader>> RecordingReader::open(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    return Error{"recording " + path + ": cannot open: " + std::strerror(errno)};
  }
  auto r = std::unique_ptr<RecordingReader>(new RecordingReader(path, f));
  std::uint8_t h[kRecordingHeaderBytes];
  if (std::fread(h, 1, sizeof h, f) != sizeof h) {
    return Error{"recording " + path + ": shorter than its 32-byte header: not a recording"};
  }
  if (std::memcmp(h, kMagic, 8) != 0) {
    return Error{"recording " + path + ": no CRUNCHRC magic: not a crunchhost recording"};
  }
  if (get32(h + 28) != crc32({h, 28})) {
    return Error{"recording " + path + ": header CRC mismatch: the header is damaged"};
  }
  const std::uint16_t version = get16(h + 8);
  if (version < 1 || version > kRecordingVersion) {
    return Error{"recording " + path + ": format version " + std::to_string(version) +
                 ", this crunchhost reads versions 1 to " + std::to_string(kRecordingVersion)};
  }
  r->version_ = version;
  const std::uint16_t header_len = get16(h + 10);
  const std::uint32_t meta_len = get32(h + 12);
  if (header_len != kRecordingHeaderBytes || meta_len > kMaxMetadata) {
    return Error{"recording " + path + ": header length fields are damaged"};
  }
  r->start_unix_ns_ = get64(h + 16);
  r->metadata_.resize(meta_len);
  if (meta_len > 0 && std::fread(r->metadata_.data(), 1, meta_len, f) != meta_len) {
    return Error{"recording " + path + ": ends inside its metadata: truncated"};
  }
  if (version >= 2 &&
      get32(h + 24) != crc32({reinterpret_cast<const std::uint8_t*>(r->metadata_.data()),
                              r->metadata_.size()})) {
    return Error{"recording " + path + ": metadata CRC mismatch: the metadata is damaged"};
  }
  r->offset_ = kRecordingHeaderBytes + meta_len;
  return r;
}

RecordingReader::Next RecordingReader::fail(const std::string& why) {
  done_ = true;
  damage_ = "recording " + path_ + ": record " + std::to_string(records_ + 1) + " at byte " +
            std::to_string(offset_) + ": " + why;
  return Next::kDamaged;
}

RecordingReader::Next RecordingReader::next(Chunk& out) {
  if (done_) return damage_.empty() ? Next::kEnd : Next::kDamaged;
  std::uint8_t h[kRecordHeaderBytes];
  const std::size_t got = std::fread(h, 1, sizeof h, file_);
  if (got == 0 && std::feof(file_)) {
    done_ = true;
    return Next::kEnd;
  }
  if (got != sizeof h) return fail("the file ends inside a record header (truncated)");
  const std::uint8_t stream = h[0];
  const std::uint16_t size = get16(h + 2);
  if (!validStream(stream) || h[1] != 0) return fail("unknown stream id (damaged)");
  if (size > kMaxChunkBytes) return fail("record size " + std::to_string(size) + " too large (damaged)");
  if (std::fread(out.bytes.data(), 1, size, file_) != size) {
    return fail("the file ends inside a record (truncated)");
  }
  std::uint8_t c[4];
  if (std::fread(c, 1, 4, file_) != 4) return fail("the file ends inside a record (truncated)");
  const std::uint32_t crc = crc32({out.bytes.data(), size}, crc32({h, sizeof h}));
  if (crc != get32(c)) return fail("CRC mismatch (damaged)");
  out.stream = static_cast<StreamId>(stream);
  out.size = size;
  out.t_ns = get64(h + 4);
  offset_ += kRecordHeaderBytes + size + 4;
  ++records_;
  return Next::kRecord;
}

}  // namespace crunch::io
