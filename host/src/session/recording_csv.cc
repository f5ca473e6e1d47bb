#include "crunch/session/recording_csv.h"

#include <algorithm>
#include <charconv>
#include <optional>
#include <utility>

#include "crunch/core/atomic_file.h"
#include "crunch/io/bridge_stream.h"
#include "crunch/io/recording.h"
#include "crunch/robot/shapelet.h"
#include "crunch/session/robot_session.h"
#include "crunch/session/session_settings.h"

namespace crunch::session {

namespace {

// One CSV file: rows gathered in a buffer, written to its AtomicFile a MiB at a time.
class CsvFile {
 public:
  static constexpr std::size_t kFlushBytes = std::size_t{1} << 20;

  explicit CsvFile(AtomicFile* file) : file_(file) {}

  CsvFile& num(double v) {
    sep();
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest round trip
    buf_.append(buf, r.ptr);
    return *this;
  }
  CsvFile& num(std::uint64_t v) {
    sep();
    buf_.append(std::to_string(v));
    return *this;
  }
  CsvFile& num(int v) {
    sep();
    buf_.append(std::to_string(v));
    return *this;
  }
  CsvFile& text(const char* s) {
    sep();
    buf_.append(s);
    return *this;
  }
  // Ends the row; writes the buffer out once it is large.
  Status end() {
    buf_ += '\n';
    first_ = true;
    ++rows_;
    if (buf_.size() < kFlushBytes) return okStatus();
    return flush();
  }
  Status flush() {
    auto st = file_->write(buf_);
    buf_.clear();
    return st;
  }
  std::uint64_t rows() const { return rows_; }

 private:
  void sep() {
    if (!first_) buf_ += ',';
    first_ = false;
  }
  AtomicFile* file_;  // owned by the export's OutputSet
  std::string buf_;
  bool first_ = true;
  std::uint64_t rows_ = 0;
};

Result<CsvFile> openCsv(OutputSet& out, const std::string& path, const char* header) {
  auto f = out.add(path);
  if (!f) return f.error();
  CsvFile csv(f.value());
  csv.text(header);
  if (auto st = csv.end(); !st) return st.error();
  return csv;
}

}  // namespace

Result<RecordingCsvSummary> exportRecordingCsv(const std::string& recording,
                                               const std::string& out_dir, bool* output_failed) {
  if (output_failed != nullptr) *output_failed = false;
  // Past the checks, a failure is the output's (a full disk), not the input's.
  const auto failedWriting = [output_failed](Error e) {
    if (output_failed != nullptr) *output_failed = true;
    return e;
  };
  // t_s counts from the earliest record: the file's order is the processing order, and a
  // Create chunk can come before bridge bytes that arrived earlier (drained later from the ring).
  std::optional<std::uint64_t> t0;
  {
    auto scan = io::RecordingReader::open(recording);
    if (!scan) return scan.error();
    io::Chunk c;
    while (scan.value()->next(c) == io::RecordingReader::Next::kRecord) {
      t0 = t0 ? std::min(*t0, c.t_ns) : c.t_ns;
    }
  }
  auto reader = io::RecordingReader::open(recording);
  if (!reader) return reader.error();
  io::RecordingReader& rec = *reader.value();
  auto options = sessionFromMetadata(rec.metadata(), "recording " + recording);
  if (!options) return options.error();
  options.value().mapping.threads = 1;  // the map is not exported: no cores for its chains
  auto created = RobotSession::create(options.value());
  if (!created) return created.error();
  RobotSession& session = *created.value();

  if (auto st = checkOutputTargets(out_dir, {"samples.csv", "contacts.csv", "odometry.csv"}); !st) {
    return Error{"--out " + st.error().message};
  }
  if (auto st = ensureDirectory(out_dir); !st) return failedWriting(st.error());
  removeStaleTemps(out_dir, {"samples.csv", "contacts.csv", "odometry.csv"});
  OutputSet out;
  auto samples = openCsv(out, out_dir + "/samples.csv",
                         "t_s,t_ns,board,seq,tick,alpha,beta,status,frames_lost,samples_dropped");
  if (!samples) return failedWriting(samples.error());
  auto contacts = openCsv(out, out_dir + "/contacts.csv",
                          "t_s,t_ns,whisk,whisker,r_m,phi_rad,oriented,face_span_m,robot_x_m,"
                          "robot_y_m,robot_theta_rad,contact_x_m,contact_y_m");
  if (!contacts) return failedWriting(contacts.error());
  auto odometry =
      openCsv(out, out_dir + "/odometry.csv", "t_s,t_ns,x_m,y_m,theta_rad,bumped,packets");
  if (!odometry) return failedWriting(odometry.error());
  CsvFile& s_csv = samples.value();
  CsvFile& c_csv = contacts.value();
  CsvFile& o_csv = odometry.value();

  // The samples' own decoder: the session's decodes the same bytes but hands its frames on
  // inside the chain; a second decoder fed the same chunks (and reset at the same marks) sees
  // the same frames.
  io::BridgeStreamDecoder decoder;
  std::uint64_t t_ns = 0;
  Status written = okStatus();
  const auto seconds = [&t0](std::uint64_t t) {
    return static_cast<double>(static_cast<std::int64_t>(t - *t0)) * 1e-9;
  };
  const auto writeContacts = [&](int whisk) {
    for (const ContactReport& rep : session.lastReports()) {
      c_csv.num(seconds(t_ns)).num(t_ns).num(whisk).num(rep.whisker).num(rep.r).num(rep.phi);
      c_csv.num(rep.oriented ? 1 : 0).num(rep.face_span);
      c_csv.num(rep.robot.x).num(rep.robot.y).num(rep.robot.theta);
      Shapelet sh;
      if (toShapelet(rep, session.options().mounts, whisk, sh)) {
        c_csv.num(sh.x).num(sh.y);
      } else {
        c_csv.text("").text("");  // a report the mapper rejects: no located point
      }
      if (auto st = c_csv.end(); !st) written = st;
    }
  };

  RecordingCsvSummary sum;
  int whisk = 0;
  io::Chunk chunk;
  io::RecordingReader::Next next;
  while (written.ok() && (next = rec.next(chunk)) == io::RecordingReader::Next::kRecord) {
    t_ns = chunk.t_ns;
    (void)session.handle(chunk);  // no recorder: cannot fail
    switch (chunk.stream) {
      case io::StreamId::kBridge:
        decoder.feed(chunk.data(), [&](const io::DecodedFrame& d) {
          s_csv.num(seconds(t_ns)).num(t_ns).num(int{d.frame.board}).num(int{d.frame.seq});
          s_csv.num(std::uint64_t{d.frame.tick}).num(int{d.frame.alpha}).num(int{d.frame.beta});
          s_csv.num(int{d.frame.status}).num(std::uint64_t{d.frames_lost});
          s_csv.num(std::uint64_t{d.samples_dropped});
          if (auto st = s_csv.end(); !st) written = st;
        });
        break;
      case io::StreamId::kCreate: {
        const Pose2 p = session.pose();
        o_csv.num(seconds(t_ns)).num(t_ns).num(p.x).num(p.y).num(p.theta);
        o_csv.num(session.bumped() ? 1 : 0).num(session.tracker().packets());
        if (auto st = o_csv.end(); !st) written = st;
        break;
      }
      case io::StreamId::kMark:
        if (chunk.size > 0 && chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kWhiskEnd)) {
          writeContacts(whisk++);
        }
        if (chunk.size > 0 &&
            chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kBridgeReconnected)) {
          decoder.reset();
        }
        break;
    }
  }
  if (!written) return failedWriting(written.error());
  if (next == io::RecordingReader::Next::kDamaged) sum.damage = rec.damage();
  sum.records = rec.records();
  // The whisk a cut-short recording left open: finish() closes it (and maps, unused here).
  if (t0) {
    (void)session.finish();
    writeContacts(whisk);
    if (!written) return failedWriting(written.error());
  }
  sum.samples = s_csv.rows() - 1;  // less the header
  sum.contacts = c_csv.rows() - 1;
  sum.odometry = o_csv.rows() - 1;
  for (CsvFile* f : {&s_csv, &c_csv, &o_csv}) {
    if (auto st = f->flush(); !st) return failedWriting(st.error());
  }
  if (auto st = out.publish(); !st) return failedWriting(st.error());
  return sum;
}

}  // namespace crunch::session
