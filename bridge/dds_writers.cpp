#include "bridge/dds_writers.hpp"

namespace dicesim::bridge {

DdsWriters::DdsWriters(const std::string& config_uri, std::uint32_t domain_id) {
  // An explicit domain: its configuration is exactly `config_uri`, whatever else is around.
  domain_ = DdsEntity(dds_create_domain(domain_id, config_uri.c_str()), "domain (check the DDS configuration)");
  participant_ = DdsEntity(dds_create_participant(domain_id, nullptr, nullptr), "participant");
  const Qos qos = latest_per_run_qos();
  prob_topic_ = DdsEntity(dds_create_topic(participant_.get(), &dicesim_dds_probabilities_v3_desc, kProbabilitiesTopic,
                                           qos.get(), nullptr),
                          "topic dicesim_probabilities");
  status_topic_ = DdsEntity(
      dds_create_topic(participant_.get(), &dicesim_dds_run_status_desc, kRunStatusTopic, qos.get(), nullptr),
      "topic dicesim_run_status");
  prob_writer_ = DdsEntity(dds_create_writer(participant_.get(), prob_topic_.get(), qos.get(), nullptr),
                           "writer dicesim_probabilities");
  status_writer_ = DdsEntity(dds_create_writer(participant_.get(), status_topic_.get(), qos.get(), nullptr),
                             "writer dicesim_run_status");
}

void DdsWriters::write(const dicesim_dds_probabilities_v3& s) {
  if (dds_write(prob_writer_.get(), &s) < 0) ++write_errors_;
}

void DdsWriters::write(const dicesim_dds_run_status& s) {
  if (dds_write(status_writer_.get(), &s) < 0) ++write_errors_;
}

void DdsWriters::dispose(std::int64_t run_id) {
  dicesim_dds_probabilities_v3 p{};
  p.run_id = run_id;
  char empty[] = "";
  p.provenance = empty;
  dds_dispose(prob_writer_.get(), &p);
  dicesim_dds_run_status s{};
  s.run_id = run_id;
  s.origin = s.scene_hash = s.fidelity = empty;
  dds_dispose(status_writer_.get(), &s);
}

}  // namespace dicesim::bridge
