// RAII for Cyclone DDS C API handles: an entity (participant, topic, writer, reader, waitset) is
// deleted with its owner, a QoS object freed with its owner. Deleting a participant deletes its
// children too, so owners are declared parent first and destroyed child first.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include <dds/dds.h>

namespace dicesim::bridge {

class DdsEntity {
 public:
  DdsEntity() = default;
  // Takes a handle straight from a dds_create_* call; a negative one is that call's error code.
  DdsEntity(dds_entity_t handle, const char* what) : handle_(handle) {
    if (handle_ < 0)
      throw std::runtime_error(std::string("DDS: cannot create ") + what + ": " + dds_strretcode(handle_));
  }
  DdsEntity(const DdsEntity&) = delete;
  DdsEntity& operator=(const DdsEntity&) = delete;
  DdsEntity(DdsEntity&& o) noexcept : handle_(std::exchange(o.handle_, 0)) {}
  DdsEntity& operator=(DdsEntity&& o) noexcept {
    if (this != &o) {
      reset();
      handle_ = std::exchange(o.handle_, 0);
    }
    return *this;
  }
  ~DdsEntity() { reset(); }

  dds_entity_t get() const { return handle_; }

 private:
  void reset() {
    // A child already deleted with its parent answers "already deleted": harmless.
    if (handle_ > 0) dds_delete(handle_);
    handle_ = 0;
  }
  dds_entity_t handle_ = 0;
};

struct QosDeleter {
  void operator()(dds_qos_t* q) const { dds_delete_qos(q); }
};
using Qos = std::unique_ptr<dds_qos_t, QosDeleter>;

// The contract of both dicesim topics, for writers and readers alike: every sample arrives
// (reliable), a late reader gets the latest sample of each run at once (transient-local), and
// only that one is kept per run (keep-last 1 per key).
inline Qos latest_per_run_qos() {
  Qos q(dds_create_qos());
  dds_qset_reliability(q.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(q.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(q.get(), DDS_HISTORY_KEEP_LAST, 1);
  return q;
}

}  // namespace dicesim::bridge
