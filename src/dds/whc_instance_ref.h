#pragma once
// A work-around for a memory leak of Cyclone DDS 0.10 (every 0.10.x; fixed upstream in 11.0 by
// commit 5cbf5c0, "Fix tkmap_instance leak in WHC"): a writer's history cache takes a reference
// on the key-to-instance map entry (tkmap) of every instance it indexes and never gives it back,
// so the entry and the serialized key it holds outlive the instance's unregistration. A writer
// of one instance per episode (the fusion center's Reports) then keeps ~300 bytes per episode
// for the rest of its life (measured, bench/README.md "Memory over long runs").
//
// Call it on the thread that has just unregistered, successfully, an instance that the writer
// had written since its last unregistration (so that the history cache indexed it and has now
// dropped it), with the instance handle dds_lookup_instance gave before the unregister:
//
//   const dds_instance_handle_t instance = dds_lookup_instance(writer, &key);
//   if (dds_unregister_instance(writer, &key) == DDS_RETCODE_OK)
//     (void)sensornet_release_unregistered_instance(writer, instance);
//
// It drops the leaked reference only when nothing else holds the entry (its count is then the
// leaked one plus its own lookup's), so an entry a local reader also holds is left alone (kept,
// never freed early). With a Cyclone other than 0.10 it does nothing.

#include <dds/dds.h>

#ifdef __cplusplus
extern "C" {
#endif

// 1 if the leaked reference was dropped (the entry is freed), 0 if there was none to drop or the
// entry is shared, -1 if the calling thread's Cyclone state is not the writer's domain.
int sensornet_release_unregistered_instance(dds_entity_t writer, dds_instance_handle_t instance);

#ifdef __cplusplus
}
#endif
