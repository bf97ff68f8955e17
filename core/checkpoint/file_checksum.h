/* A checksum trailer on checkpoint files: the 64-bit FNV-1a hash of every
 * byte before it, after 8 bytes of magic, appended once the HDF5 file is
 * whole. A restart verifies it before the HDF5 library reads a byte, so a
 * changed, truncated or foreign file is refused with one message instead of
 * being parsed (docs/reliability.md, "Checkpoints and restart"). One
 * changed byte always changes the hash (each step of FNV-1a is a bijection
 * of the state); several changes escape it with probability 2^-64. */
#ifndef SLUICE_FILE_CHECKSUM_H
#define SLUICE_FILE_CHECKSUM_H

#include <stddef.h>
#include <stdint.h>

#define SLUICE_CHECKSUM_MAGIC "SLUICE\x01\x0f" /* 8 bytes */
#define SLUICE_CHECKSUM_BYTES 16              /* the magic, then the hash (little-endian) */

uint64_t sluice_checksum_update(uint64_t hash, const void *data, size_t size);
#define SLUICE_CHECKSUM_START 0xcbf29ce484222325ull

/* The trailer of `size` bytes of data in `trailer` (SLUICE_CHECKSUM_BYTES). */
void sluice_checksum_trailer(const void *data, size_t size, unsigned char *trailer);

/* Appends the trailer of the whole file at `path` to it. 0, or -1 with a
 * message in error. */
int sluice_checksum_append(const char *path, char *error, size_t error_size);

/* Checks the trailer of the file at `path`: 0 when it holds, -1 with the
 * reason in error (no trailer, truncated, content changed, unreadable). */
int sluice_checksum_verify(const char *path, char *error, size_t error_size);

#endif
