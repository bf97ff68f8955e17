/* The checksum trailer of checkpoint files (file_checksum.h). */
#define _GNU_SOURCE
#include "file_checksum.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

uint64_t sluice_checksum_update(uint64_t hash, const void *data, size_t size)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < size; i++) {
        hash ^= p[i];
        hash *= 0x100000001b3ull;
    }
    return hash;
}

static void put_trailer(uint64_t hash, unsigned char *trailer)
{
    memcpy(trailer, SLUICE_CHECKSUM_MAGIC, 8);
    for (int i = 0; i < 8; i++)
        trailer[8 + i] = (unsigned char)(hash >> (8 * i));
}

void sluice_checksum_trailer(const void *data, size_t size, unsigned char *trailer)
{
    put_trailer(sluice_checksum_update(SLUICE_CHECKSUM_START, data, size), trailer);
}

/* The hash of the first `length` bytes of f, read in blocks. */
static int hash_prefix(FILE *f, long long length, uint64_t *hash)
{
    enum { BLOCK = 1 << 20 };
    unsigned char *buffer = malloc(BLOCK);
    if (!buffer)
        return -1;
    uint64_t h = SLUICE_CHECKSUM_START;
    long long left = length;
    int status = 0;
    while (left > 0) {
        size_t want = left < BLOCK ? (size_t)left : BLOCK;
        if (fread(buffer, 1, want, f) != want) {
            status = -1;
            break;
        }
        h = sluice_checksum_update(h, buffer, want);
        left -= (long long)want;
    }
    free(buffer);
    *hash = h;
    return status;
}

static long long file_length(FILE *f)
{
    if (fseeko(f, 0, SEEK_END) != 0)
        return -1;
    long long n = (long long)ftello(f);
    return fseeko(f, 0, SEEK_SET) == 0 ? n : -1;
}

int sluice_checksum_append(const char *path, char *error, size_t error_size)
{
    FILE *f = fopen(path, "r+b");
    if (!f) {
        snprintf(error, error_size, "cannot open '%s' for its checksum: %s", path,
                 strerror(errno));
        return -1;
    }
    uint64_t hash = 0;
    long long n = file_length(f);
    unsigned char trailer[SLUICE_CHECKSUM_BYTES];
    int status = n < 0 || hash_prefix(f, n, &hash) != 0 ? -1 : 0;
    if (status == 0) {
        put_trailer(hash, trailer);
        status = fseeko(f, 0, SEEK_END) != 0 ||
                         fwrite(trailer, 1, sizeof trailer, f) != sizeof trailer ||
                         fflush(f) != 0
                     ? -1
                     : 0;
    }
    if (status != 0)
        snprintf(error, error_size, "cannot add the checksum to '%s': %s", path,
                 errno ? strerror(errno) : "read or write failed");
    if (fclose(f) != 0 && status == 0) {
        snprintf(error, error_size, "cannot add the checksum to '%s': %s", path, strerror(errno));
        status = -1;
    }
    return status;
}

int sluice_checksum_verify(const char *path, char *error, size_t error_size)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(error, error_size, "cannot read it: %s", strerror(errno));
        return -1;
    }
    long long n = file_length(f);
    unsigned char trailer[SLUICE_CHECKSUM_BYTES];
    uint64_t hash = 0;
    int status = -1;
    if (n < 0) {
        snprintf(error, error_size, "cannot read it: %s", strerror(errno));
    } else if (n < SLUICE_CHECKSUM_BYTES ||
               fseeko(f, n - SLUICE_CHECKSUM_BYTES, SEEK_SET) != 0 ||
               fread(trailer, 1, sizeof trailer, f) != sizeof trailer ||
               memcmp(trailer, SLUICE_CHECKSUM_MAGIC, 8) != 0) {
        snprintf(error, error_size,
                 "it does not end in a sluice checksum: not a checkpoint, written by a sluice "
                 "before checkpoints carried one, or cut short");
    } else if (fseeko(f, 0, SEEK_SET) != 0 ||
               hash_prefix(f, n - SLUICE_CHECKSUM_BYTES, &hash) != 0) {
        snprintf(error, error_size, "cannot read it: %s", errno ? strerror(errno) : "short read");
    } else {
        uint64_t stored = 0;
        for (int i = 0; i < 8; i++)
            stored |= (uint64_t)trailer[8 + i] << (8 * i);
        if (stored != hash)
            snprintf(error, error_size,
                     "its checksum does not match its %lld bytes: the file changed after it "
                     "was written (a damaged disk or copy, or an edit)",
                     n - SLUICE_CHECKSUM_BYTES);
        else
            status = 0;
    }
    fclose(f);
    return status;
}
