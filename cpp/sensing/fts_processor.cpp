#include "ernest/sensing/fts_processor.hpp"

#include <cmath>

#include "ernest/common/validation.hpp"

namespace ernest::sensing {

void FtsFilterOptions::validate() const {
  require_positive("FtsFilterOptions", "sample_rate", sample_rate);
  try {
    require_in_range("FtsFilterOptions", "cutoff", cutoff, 1e-6, sample_rate / 2.0);
  } catch (const std::invalid_argument& e) {  // a coupled bound: name the other field too
    throw std::invalid_argument(std::string(e.what()) +
                                " (the upper bound is sample_rate / 2, the Nyquist frequency)");
  }
}

FtsProcessor::FtsProcessor(const FtsFilterOptions& options) : options_(options) {
  options_.validate();
  alpha_ = 1.0 - std::exp(-2.0 * M_PI * options_.cutoff / options_.sample_rate);
}

void FtsProcessor::reset(const Eigen::Ref<const Wrenches>& initial) {
  require(initial.allFinite(), "FtsProcessor.reset: initial wrenches must be finite");
  filtered_ = initial;
  initialised_ = true;
}

void FtsProcessor::update(const Eigen::Ref<const Wrenches>& raw) {
  require(raw.allFinite(), "FtsProcessor.update: raw wrenches must be finite");
  if (!initialised_) {
    reset(raw);
    return;
  }
  filtered_ += alpha_ * (raw - filtered_);
}

void FtsProcessor::set_bias(const Eigen::Ref<const Wrenches>& bias) {
  require(bias.allFinite(), "FtsProcessor.set_bias: bias must be finite");
  bias_ = bias;
}

Wrenches FtsProcessor::processed() const {
  Wrenches out = filtered_ - bias_;
  const Eigen::Matrix<double, 1, 6> mean = out.colwise().mean();
  out.rowwise() -= mean;  // §4.2: remove drifts common to all four sensors
  return out;
}

}  // namespace ernest::sensing
