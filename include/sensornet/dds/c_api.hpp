#pragma once
// The seam between the C++ layer and the Cyclone DDS C library: every Cyclone call that creates,
// deletes, writes, reads or waits goes through one table of function pointers. Production code
// uses realCApi(); a test copies it, replaces one entry with a fake and hands the copy to a
// Domain, so an error path (a write timing out, a create failing) runs against real Cyclone
// everywhere else, without breaking the network.
//
//   CApi api = realCApi();
//   api.write = [](dds_entity_t, const void*) -> dds_return_t { return DDS_RETCODE_TIMEOUT; };
//   Domain domain(config, api);   // `api` must outlive the domain and everything made from it
//
// Pure memory helpers (QoS and listener objects, dds_sample_free, dds_strretcode) are called
// directly.

#include <dds/dds.h>

namespace sensornet::dds {

struct CApi {
  // Entities.
  dds_entity_t (*create_domain)(dds_domainid_t, const char*) = ::dds_create_domain;
  dds_entity_t (*create_participant)(dds_domainid_t, const dds_qos_t*,
                                     const dds_listener_t*) = ::dds_create_participant;
  dds_entity_t (*create_topic)(dds_entity_t, const dds_topic_descriptor_t*, const char*,
                               const dds_qos_t*, const dds_listener_t*) = ::dds_create_topic;
  dds_entity_t (*create_writer)(dds_entity_t, dds_entity_t, const dds_qos_t*,
                                const dds_listener_t*) = ::dds_create_writer;
  dds_entity_t (*create_reader)(dds_entity_t, dds_entity_t, const dds_qos_t*,
                                const dds_listener_t*) = ::dds_create_reader;
  dds_entity_t (*create_readcondition)(dds_entity_t, uint32_t) = ::dds_create_readcondition;
  dds_entity_t (*create_guardcondition)(dds_entity_t) = ::dds_create_guardcondition;
  dds_entity_t (*create_waitset)(dds_entity_t) = ::dds_create_waitset;
  dds_return_t (*delete_entity)(dds_entity_t) = ::dds_delete;
  dds_return_t (*get_status_mask)(dds_entity_t, uint32_t*) = ::dds_get_status_mask;
  dds_return_t (*set_status_mask)(dds_entity_t, uint32_t) = ::dds_set_status_mask;
  dds_return_t (*set_listener)(dds_entity_t, const dds_listener_t*) = ::dds_set_listener;

  // Waiting.
  dds_return_t (*waitset_attach)(dds_entity_t, dds_entity_t, dds_attach_t) = ::dds_waitset_attach;
  dds_return_t (*waitset_detach)(dds_entity_t, dds_entity_t) = ::dds_waitset_detach;
  dds_return_t (*waitset_wait)(dds_entity_t, dds_attach_t*, size_t,
                               dds_duration_t) = ::dds_waitset_wait;
  dds_return_t (*set_guardcondition)(dds_entity_t, bool) = ::dds_set_guardcondition;
  dds_return_t (*take_guardcondition)(dds_entity_t, bool*) = ::dds_take_guardcondition;

  // Writing.
  dds_return_t (*write)(dds_entity_t, const void*) = ::dds_write;
  dds_return_t (*write_ts)(dds_entity_t, const void*, dds_time_t) = ::dds_write_ts;
  void (*write_flush)(dds_entity_t) = ::dds_write_flush;
  dds_return_t (*dispose)(dds_entity_t, const void*) = ::dds_dispose;
  dds_return_t (*unregister_instance)(dds_entity_t, const void*) = ::dds_unregister_instance;
  dds_return_t (*wait_for_acks)(dds_entity_t, dds_duration_t) = ::dds_wait_for_acks;
  dds_return_t (*get_publication_matched_status)(dds_entity_t, dds_publication_matched_status_t*) =
      ::dds_get_publication_matched_status;

  // Reading.
  dds_return_t (*take)(dds_entity_t, void**, dds_sample_info_t*, size_t, uint32_t) = ::dds_take;
  dds_return_t (*read)(dds_entity_t, void**, dds_sample_info_t*, size_t, uint32_t) = ::dds_read;
  dds_return_t (*get_subscription_matched_status)(
      dds_entity_t, dds_subscription_matched_status_t*) = ::dds_get_subscription_matched_status;
};

// The table of the real Cyclone functions (immutable, shared by everyone).
[[nodiscard]] const CApi& realCApi() noexcept;

}  // namespace sensornet::dds
