// The signal pipeline's settings (pipeline.h): the contact detectors, the orientation window and
// the episode limits. Carried in the models file (models_io.h) because the models are only
// valid for the settings they were trained with: the radial lines' f1 and the templates'
// windows depend on the detector's onset threshold and filters.
#pragma once

#include <cstdint>

#include "crunch/core/result.h"
#include "crunch/signal/contact_detector.h"
#include "crunch/signal/contact_ramp.h"
#include "crunch/signal/window.h"

namespace crunch::signal {

struct PipelineOptions {
  ContactDetectorOptions detector;
  WindowOptions window;
  std::int64_t max_episode_samples = 20000;  // 10 s; at least window.samples
  // An episode is reliable if no whisker was lost during it and every whisker held at most
  // this fraction of its samples (sample.h: held samples are not measurements).
  double max_held_fraction = 0.05;
  // The deflection ramp against the body's heading that locates a contact (contact_ramp.h).
  RampOptions ramp;
  // okStatus(), or an Error naming the bad field.
  Status validate() const;
};

}  // namespace crunch::signal
