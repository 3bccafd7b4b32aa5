#pragma once

namespace solo {

// Makes glibc's malloc keep the memory of freed large buffers for reuse instead of handing it
// back to the kernel: no block is mmapped (every one comes from the heap) and the heap's top is
// never trimmed.
//
// Why: the night pipeline allocates and frees buffers of tens to hundreds of MB stage after
// stage (depth maps, the optimiser's vectors, the OpenMesh arrays, the ray caster's buffers).
// With glibc's defaults each of them is mmapped, page-faulted in 4 KiB pages on first touch and
// unmapped on free: 1.1 M page faults and 3.5 s of system time for one 1080p scene. Keeping
// freed memory cuts that to 0.4 M faults and 1.6 s; the optimise, mesh and scene stages run
// about 0.7, 0.6 and 0.15 s faster, the whole run 0.92x (docs/presets.md). The price is a peak
// resident size 0.2 GiB higher at 1080p (1.62 -> 1.80 GiB).
//
// Call once at the start of a process, before any thread starts. Returns false when the
// C library does not accept the settings (not glibc); nothing else changes then.
bool keepFreedLargeBuffersForReuse();

}  // namespace solo
