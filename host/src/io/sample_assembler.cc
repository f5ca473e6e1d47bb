#include "crunch/io/sample_assembler.h"

#include <algorithm>
#include <cassert>

namespace crunch::io {

SampleAssembler::SampleAssembler(const Options& options) : options_(options) {
  assert(options_.max_lag >= 1 && options_.max_lag < kQueue);
}

int SampleAssembler::whiskerOf(std::uint8_t board) const {
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (options_.board_of_whisker[static_cast<std::size_t>(w)] == board) return w;
  }
  return -1;
}

void SampleAssembler::enqueue(int w, const signal::WhiskerReading& r) {
  const auto i = static_cast<std::size_t>(w);
  if (count_[i] == kQueue) {  // cannot happen while max_lag < kQueue; keep the newest anyway
    head_[i] = (head_[i] + 1) % kQueue;
    --count_[i];
  }
  queue_[i][static_cast<std::size_t>((head_[i] + count_[i]) % kQueue)] = r;
  ++count_[i];
}

bool SampleAssembler::ready() {
  const int most = *std::max_element(count_.begin(), count_.end());
  const int least = *std::min_element(count_.begin(), count_.end());
  if (least > 0) return true;
  if (most <= options_.max_lag) return false;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    if (count_[static_cast<std::size_t>(w)] == 0) {
      enqueue(w, placeholder());
      ++counters_.silent_fills;
      ++debt_[static_cast<std::size_t>(w)];
    }
  }
  return true;
}

const signal::SampleFrame& SampleAssembler::pop() {
  for (std::size_t w = 0; w < signal::kWhiskers; ++w) {
    out_[w] = queue_[w][static_cast<std::size_t>(head_[w])];
    head_[w] = (head_[w] + 1) % kQueue;
    --count_[w];
  }
  ++counters_.samples;
  return out_;
}

void SampleAssembler::reset() {
  head_.fill(0);
  count_.fill(0);
  debt_.fill(0);
}

}  // namespace crunch::io
