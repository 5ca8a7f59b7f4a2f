// See whc_instance_ref.h. Uses Cyclone's internal headers (shipped with cyclonedds-dev), so it is
// C and kept to this one file.
#include "whc_instance_ref.h"

#include <dds/version.h>

#if DDS_VERSION_MAJOR == 0 && DDS_VERSION_MINOR == 10

#include <dds/ddsi/ddsi_domaingv.h>
#include <dds/ddsi/ddsi_tkmap.h>
#include <dds/ddsi/q_thread.h>

// The domain the calling thread worked in last: Cyclone marks the thread awake in the writer's
// domain during dds_lookup_instance and dds_unregister_instance and leaves the pointer set.
static struct ddsi_domaingv *lastDomainOfThisThread(dds_entity_t writer) {
  struct thread_state *const thread = lookup_thread_state();
  struct ddsi_domaingv *const gv = ddsrt_atomic_ldvoidp(&thread->gv);
  dds_domainid_t domain = 0;
  if (gv == NULL || dds_get_domainid(writer, &domain) != DDS_RETCODE_OK ||
      gv->config.domainId != domain) {
    return NULL;
  }
  return gv;
}

int sensornet_release_unregistered_instance(dds_entity_t writer, dds_instance_handle_t instance) {
  if (instance == DDS_HANDLE_NIL) return 0;
  struct ddsi_domaingv *const gv = lastDomainOfThisThread(writer);
  if (gv == NULL) return -1;
  struct thread_state *const thread = lookup_thread_state();
  thread_state_awake(thread, gv);
  int released = 0;
  // A linear scan of the map; small once unregistered instances leave it.
  struct ddsi_tkmap_instance *const tk = ddsi_tkmap_find_by_id(gv->m_tkmap, instance);
  if (tk != NULL) {
    // Ours and the history cache's leaked one: nobody else holds it.
    if (ddsrt_atomic_ld32(&tk->m_refc) == 2) {
      ddsi_tkmap_instance_unref(gv->m_tkmap, tk);
      released = 1;
    }
    ddsi_tkmap_instance_unref(gv->m_tkmap, tk);
  }
  thread_state_asleep(thread);
  return released;
}

#else

int sensornet_release_unregistered_instance(dds_entity_t writer, dds_instance_handle_t instance) {
  (void)writer;
  (void)instance;
  return 0;
}

#endif
