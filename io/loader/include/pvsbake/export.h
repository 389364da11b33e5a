// SPDX-License-Identifier: MIT
/* pvsbake runtime loader: PVSBAKE_API marks the functions of the C API (pvsbake/loader_c.h,
 * pvsbake/occlusion_c.h), the only symbols the shared library libpvsbake_loader.so exports; it is built
 * with hidden visibility and a linker version script (io/loader/loader.map), see docs/LOADER.md,
 * "Stability". For the static library the mark changes nothing. */
#ifndef PVSBAKE_EXPORT_H
#define PVSBAKE_EXPORT_H

#if defined(__GNUC__) || defined(__clang__)
#define PVSBAKE_API __attribute__((visibility("default")))
#else
#define PVSBAKE_API
#endif

#endif /* PVSBAKE_EXPORT_H */
