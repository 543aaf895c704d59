// The bridge's DDS side: one participant (on the configuration it is given), the topics
// `dicesim_probabilities` and `dicesim_run_status`, one writer each (latest_per_run_qos).
#pragma once

#include <cstdint>
#include <string>

#include "bridge/dds_entity.hpp"
#include "dicesim_dds/probabilities.h"
#include "dicesim_dds/run_status.h"

namespace dicesim::bridge {

inline constexpr const char* kProbabilitiesTopic = "dicesim_probabilities";
inline constexpr const char* kRunStatusTopic = "dicesim_run_status";

class DdsWriters {
 public:
  // `config_uri`: a Cyclone configuration ("file://..." or XML) for `domain_id`.
  // Throws std::runtime_error if any entity cannot be created.
  DdsWriters(const std::string& config_uri, std::uint32_t domain_id);

  void write(const dicesim_dds_probabilities_v3& s);
  void write(const dicesim_dds_run_status& s);
  void dispose(std::int64_t run_id);  // both topics: the run is gone for late subscribers too
  std::int64_t write_errors() const { return write_errors_; }

 private:
  // Declared parent first: destroyed children first.
  DdsEntity domain_, participant_, prob_topic_, status_topic_, prob_writer_, status_writer_;
  std::int64_t write_errors_ = 0;
};

}  // namespace dicesim::bridge
