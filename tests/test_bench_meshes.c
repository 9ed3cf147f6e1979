/* The bench harness's SHA-256 (bench/common/meshes.c), which bench_tables uses to verify the test
 * meshes before measuring: the FIPS 180-2 Appendix B test vectors (independent reference digests)
 * on messages of 0, 3 and 56 bytes (the last needs a second padding block), and a 1,000,000-byte
 * message of 'a' (many blocks); and meshes_verify on a directory without the meshes. */
#include "../bench/common/meshes.h"
#include "harness.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int digest_of(const char *text, size_t len, size_t repeat, char hex[65])
{
    char path[] = "/tmp/shl_sha256_XXXXXX";
    const int fd = mkstemp(path);
    if (fd < 0) return -1;
    FILE *f = fdopen(fd, "wb");
    int st = !f;
    for (size_t i = 0; i < repeat && !st; ++i) st = fwrite(text, 1, len, f) != len;
    if (f) st |= fclose(f) != 0;
    st = st || sha256_file(path, hex);
    unlink(path);
    return st ? -1 : 0;
}

SHL_TEST(bench_sha256_fips_vectors)
{
    static const struct {
        const char *text;
        size_t repeat;
        const char *want;
    } v[] = {
        {"", 1, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"},
        {"abc", 1, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"},
        {"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq", 1,
         "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"},
        {"a", 1000000, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"},
    };
    for (unsigned i = 0; i < sizeof v / sizeof v[0]; ++i) {
        char hex[65];
        CHECK(digest_of(v[i].text, strlen(v[i].text), v[i].repeat, hex) == 0);
        if (strcmp(hex, v[i].want)) harness_fail(__FILE__, __LINE__, "vector %u: got %s, want %s", i, hex, v[i].want);
    }
    char hex[65];
    CHECK(sha256_file("/nonexistent/mesh.obj", hex) == -1);
}

SHL_TEST(bench_meshes_verify_reports_missing)
{
    char err[2048];
    CHECK(meshes_verify("/nonexistent", err, sizeof err) == -1);
    for (int i = 0; i < meshes_count; ++i) CHECK(strstr(err, meshes_known[i].file) != NULL);
    CHECK(meshes_find("teapot.obj") != NULL && meshes_find("dragon.obj") == NULL);
    harness_note("%d meshes named in the error", meshes_count);
}
