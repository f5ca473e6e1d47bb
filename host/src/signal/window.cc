#include "crunch/signal/window.h"

#include <cassert>
#include <string>

namespace crunch::signal {

Status WindowOptions::validate() const {
  if (samples < 1) return Error{"window.samples: expected >= 1, got " + std::to_string(samples)};
  if (decimation < 1) {
    return Error{"window.decimation: expected >= 1, got " + std::to_string(decimation)};
  }
  if (samples % decimation != 0) {
    return Error{"window.decimation: " + std::to_string(decimation) + " does not divide " +
                 "window.samples " + std::to_string(samples)};
  }
  return okStatus();
}

WindowRecorder::WindowRecorder(const WindowOptions& options) : options_(options) {
  assert(options.validate().ok());
  window_.decimation = options.decimation;
  window_.data = WindowMatrix::Zero(kChannels, options.columns());
}

void WindowRecorder::start() {
  window_.data.setZero();
  block_sum_.fill(0.0);
  in_block_ = 0;
  recorded_ = 0;
}

bool WindowRecorder::push(const std::array<double, kChannels>& channels) {
  if (full()) return true;
  for (int c = 0; c < kChannels; ++c) block_sum_[c] += channels[c];
  ++recorded_;
  if (++in_block_ == options_.decimation) {
    const int column = recorded_ / options_.decimation - 1;
    for (int c = 0; c < kChannels; ++c) {
      window_.data(c, column) = block_sum_[c] / options_.decimation;
      block_sum_[c] = 0.0;
    }
    in_block_ = 0;
  }
  return full();
}

ContactWindow decimateWindow(const WindowMatrix& full_rate, int decimation) {
  assert(decimation >= 1 && full_rate.cols() % decimation == 0);
  ContactWindow w;
  w.decimation = decimation;
  const Eigen::Index columns = full_rate.cols() / decimation;
  w.data.resize(kChannels, columns);
  for (Eigen::Index j = 0; j < columns; ++j) {
    w.data.col(j) = full_rate.middleCols(j * decimation, decimation).rowwise().mean();
  }
  return w;
}

}  // namespace crunch::signal
