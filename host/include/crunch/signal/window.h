// The 2 s contact window (paper §2.5): "Data was aligned to initial contacts, low pass filtered
// (17Hz) ..., recorded for 2s, and smoothed with a five-point moving average." The window holds
// the 8 smoothed deflection channels (4 whiskers x Alpha, Beta; radians relative to rest) from
// the first contact of any whisker on, 4000 samples at 2 kHz.
//
// Decimation (docs/SIGNAL.md, "Template decimation"). The window may be stored as the means of
// consecutive blocks of `decimation` samples (default 20: 4000 samples -> 200 columns, 100 Hz).
// After the 17 Hz low-pass nothing of the signal lives above 50 Hz, and the block mean is a
// further anti-aliasing filter, so eq. 3's mean squared error over 200 columns is that over
// 4000 samples less the high-frequency part of the noise, nearly the same for every template:
// decisions change only where two templates nearly tie (tested). Templates and the models file
// become 20 times smaller. Training and classification must use the same decimation; the
// orientation model records it.
#pragma once

#include <Eigen/Core>
#include <array>

#include "crunch/core/result.h"
#include "crunch/signal/sample.h"

namespace crunch::signal {

// Rows: channels (channelOf(whisker, axis)); columns: time.
using WindowMatrix = Eigen::Matrix<double, kChannels, Eigen::Dynamic>;

struct WindowOptions {
  int samples = 4000;   // 2 s at 2 kHz (paper §2.5)
  int decimation = 20;  // block mean of this many samples per column; 1 = none
  int columns() const { return samples / decimation; }
  // okStatus(), or an Error: samples and decimation positive, samples a multiple of decimation.
  Status validate() const;
};

struct ContactWindow {
  int decimation = 1;  // samples per column
  WindowMatrix data;   // kChannels x (samples / decimation), radians
};

// Records one window, sample by sample. Allocates its matrix once, at construction; push() does
// not allocate. Not thread-safe.
class WindowRecorder {
 public:
  // Asserts `options.validate()`.
  explicit WindowRecorder(const WindowOptions& options = {});

  // Empties the window and starts a new one.
  void start();
  // Adds one sample of the 8 channels. Ignored once full(). Returns full().
  bool push(const std::array<double, kChannels>& channels);
  bool full() const { return recorded_ == options_.samples; }
  int samplesRecorded() const { return recorded_; }
  // The window; columns not yet recorded are 0.
  const ContactWindow& window() const { return window_; }
  const WindowOptions& options() const { return options_; }

 private:
  WindowOptions options_;
  ContactWindow window_;
  std::array<double, kChannels> block_sum_{};
  int in_block_ = 0;
  int recorded_ = 0;
};

// The offline equivalent of WindowRecorder: block means of a full-rate kChannels x samples
// matrix. Asserts samples % decimation == 0.
ContactWindow decimateWindow(const WindowMatrix& full_rate, int decimation);

}  // namespace crunch::signal
