/* libFuzzer harness: fuzzer bytes as a scene YAML file, through the same entry point the CLI and
 * the node use (f3r_scene_load takes a path). The bytes go into an anonymous in-memory file
 * (memfd) that is loaded as /proc/self/fd/N, so the core needs no from-memory API. A scene that
 * validates is built into a model (f3r_model_create), whose initial state is computed; all is
 * freed. Invariants: the loader never reads or writes out of bounds (ASan, UBSan); a scene it
 * accepts satisfies f3r_scene_validate; an error always carries a message; a model built from an
 * accepted scene has nq = 9 + sum of its links' modes within 9..F3R_MAX_Q.
 *
 *   scripts/ci/fuzz [SECONDS]   builds this with clang -fsanitize=fuzzer,address,undefined */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "flex3rpr/model.h"
#include "flex3rpr/scene.h"

static int memfd = -1;
static char memfd_path[64];

static void fail(const char* what, const f3r_error* err) {
  fprintf(stderr, "fuzz_scene: invariant broken: %s (%s)\n", what, err ? err->message : "");
  abort();
}

int LLVMFuzzerTestOneInput(const unsigned char* data, size_t size) {
  if (memfd < 0) {
    memfd = memfd_create("fuzz_scene.yaml", 0);
    if (memfd < 0) {
      perror("memfd_create");
      abort();
    }
    snprintf(memfd_path, sizeof memfd_path, "/proc/self/fd/%d", memfd);
  }
  if (ftruncate(memfd, 0) != 0) abort();
  size_t done = 0;
  while (done < size) {
    const ssize_t n = pwrite(memfd, data + done, size - done, (off_t)done);
    if (n <= 0) abort();
    done += (size_t)n;
  }

  f3r_scene scene;
  memset(&scene, 0xA5, sizeof scene); /* must be left untouched on error, fully set on success */
  f3r_error err;
  memset(&err, 0, sizeof err);
  const f3r_status st = f3r_scene_load(memfd_path, &scene, &err);
  if (st != F3R_OK) {
    if (err.code != st || err.message[0] == '\0')
      fail("an error without its code or message", &err);
    if (memchr(err.message, '\0', sizeof err.message) == NULL) fail("unterminated message", NULL);
    return 0;
  }
  f3r_error again;
  if (f3r_scene_validate(&scene, &again) != F3R_OK)
    fail("a loaded scene does not validate", &again);

  f3r_model* model = NULL;
  if (f3r_model_create(&scene, &model, &err) == F3R_OK) {
    int modes = 0;
    for (int i = 0; i < 3; ++i) {
      if (f3r_model_link(model, i)->modes < 0 || f3r_model_link(model, i)->modes > F3R_MAX_MODES)
        fail("a link's mode count out of range", NULL);
      modes += f3r_model_link(model, i)->modes;
    }
    if (f3r_model_nq(model) != 9 + modes || f3r_model_nq(model) > F3R_MAX_Q)
      fail("nq is not 9 + sum of modes", NULL);
    double q[F3R_MAX_Q], v[F3R_MAX_Q];
    if (f3r_model_initial_state(model, q, v) == F3R_OK) {
      for (int n = 0; n < f3r_model_nq(model); ++n)
        if (!isfinite(q[n]) || !isfinite(v[n])) fail("a non-finite initial state", NULL);
    }
    f3r_model_destroy(model);
  } else if (model != NULL) {
    fail("f3r_model_create failed but returned a model", &err);
  } else if (err.message[0] == '\0') {
    fail("f3r_model_create failed without a message", &err);
  }
  f3r_scene_free(&scene);
  return 0;
}
