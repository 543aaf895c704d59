/* An external subscriber to a dicesim run over DDS: plain C, the Cyclone DDS C API and the
 * types idlc generates from dicesim's messages/ IDL files -- nothing else of dicesim. Prints one line
 * per sample of `dicesim_probabilities` (type dicesim_dds::probabilities_v3: any number of outcomes,
 * as bounded sequences) and `dicesim_run_status`.
 *
 *   dicesim_dds_subscriber [--json] [--topic probabilities|status|both] [--run ID]
 *                          [--count N] [--until-finished] [--timeout S]
 *
 * Its QoS matches the bridge's writers (reliable, transient-local, keep-last 1), so started
 * late it first gets each run's latest sample. Cyclone reads its configuration from
 * $CYCLONEDDS_URI like any Cyclone program, e.g.
 *   CYCLONEDDS_URI=file://$PWD/bridge/cyclonedds-loopback.xml dicesim_dds_subscriber
 * Exit: 0 done (Ctrl-C, --count reached, finished run seen), 3 --timeout passed first,
 * 2 bad usage, 1 DDS failure.
 */
#include <inttypes.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "dicesim_dds/probabilities.h"
#include "dicesim_dds/run_status.h"

#define MAX_SAMPLES 16

static volatile sig_atomic_t stop_requested = 0;
static void on_signal(int sig) {
  (void)sig;
  stop_requested = 1;
}

static int64_t now_utime(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static const char* state_name(dicesim_dds_run_state s) {
  switch (s) {
    case dicesim_dds_RUN_ANNOUNCED: return "announced";
    case dicesim_dds_RUN_RUNNING: return "running";
    case dicesim_dds_RUN_FINISHED: return "finished";
    case dicesim_dds_RUN_SILENT: return "silent";
  }
  return "?";
}

/* rx_utime - utime is the latency from the aggregator (same host, same clock). */
static void print_probabilities(const dicesim_dds_probabilities_v3* m, int json, int64_t rx) {
  uint32_t f, n = m->labels._length;
  /* The sequences have one entry per outcome; a sample whose lengths differ prints the common part. */
  if (m->counts._length < n) n = m->counts._length;
  if (m->p._length < n) n = m->p._length;
  if (m->ci_lo._length < n) n = m->ci_lo._length;
  if (m->ci_hi._length < n) n = m->ci_hi._length;
  if (json) {
    printf("{\"topic\":\"dicesim_probabilities\",\"run_id\":%" PRId64 ",\"utime\":%" PRId64 ",\"rx_utime\":%" PRId64
           ",\"done\":%" PRId64 ",\"total\":%" PRId64 ",\"finished\":%s,\"settled\":%" PRId64
           ",\"unresolved\":%" PRId64 ",\"invalid\":%" PRId64 ",\"workers\":%d,\"faces\":[",
           m->run_id, m->utime, rx, m->done, m->total, m->finished ? "true" : "false", m->settled, m->unresolved,
           m->invalid, m->workers);
    for (f = 0; f < n; ++f)
      printf("%s{\"face\":%d,\"count\":%" PRId64 ",\"p\":%.17g,\"ci95\":[%.17g,%.17g]}", f ? "," : "",
             m->labels._buffer[f], m->counts._buffer[f], m->p._buffer[f], m->ci_lo._buffer[f], m->ci_hi._buffer[f]);
    /* corrections in corrections.hpp's order; the provenance is itself a JSON object (null if none). */
    printf("],\"corrections\":[");
    for (f = 0; f < 9; ++f) printf("%s%" PRId64, f ? "," : "", m->corrections[f]);
    printf("],\"provenance\":%s}\n", m->provenance && m->provenance[0] ? m->provenance : "null");
  } else {
    printf("run %" PRId64 " %s %" PRId64 "/%" PRId64 " tosses, %d workers |", m->run_id,
           m->finished ? "FINISHED" : "running", m->done, m->total, m->workers);
    for (f = 0; f < n; ++f) printf(" %d: %.4f", m->labels._buffer[f], m->p._buffer[f]);
    printf(" | %.1f ms after publish\n", (double)(rx - m->utime) / 1000.0);
  }
}

static void print_status(const dicesim_dds_run_status* s, int json) {
  if (json)
    printf("{\"topic\":\"dicesim_run_status\",\"run_id\":%" PRId64 ",\"utime\":%" PRId64
           ",\"state\":\"%s\",\"origin\":\"%s\",\"scene_hash\":\"%s\",\"fidelity\":\"%s\",\"seed\":%" PRId64
           ",\"total_tosses\":%" PRId64 ",\"done\":%" PRId64 ",\"workers\":%d,\"workers_refused\":%d}\n",
           s->run_id, s->utime, state_name(s->state), s->origin, s->scene_hash, s->fidelity, s->seed,
           s->total_tosses, s->done, s->workers, s->workers_refused);
  else
    printf("run %" PRId64 " status %s: %s (%s, seed %" PRId64 "), %" PRId64 "/%" PRId64 " tosses, %d workers\n",
           s->run_id, state_name(s->state), s->origin, s->fidelity, s->seed, s->done, s->total_tosses, s->workers);
}

static void usage(FILE* out) {
  fprintf(out,
          "usage: dicesim_dds_subscriber [--json] [--topic probabilities|status|both] [--run ID]\n"
          "                              [--count N] [--until-finished] [--timeout S]\n"
          "Prints every sample of the DDS topics dicesim_probabilities and dicesim_run_status.\n"
          "  --json            one JSON object per line\n"
          "  --run ID          only this run\n"
          "  --count N         exit 0 after N samples\n"
          "  --until-finished  exit 0 after a run's finished answer\n"
          "  --timeout S       exit 3 if not done after S seconds\n"
          "Configuration: $CYCLONEDDS_URI, e.g. file://$PWD/bridge/cyclonedds-loopback.xml\n");
}

int main(int argc, char** argv) {
  int json = 0, want_prob = 1, want_status = 1, until_finished = 0, i;
  long count = -1, seen = 0;
  double timeout_s = -1.0;
  int64_t run_filter = 0;
  int exit_code = 0, done = 0;
  dds_entity_t participant, topics[2], readers[2], waitset;
  dds_qos_t* qos;
  const dds_time_t started = dds_time(); /* --timeout counts from here, DDS set-up included */
  dds_time_t deadline;

  for (i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "--json")) json = 1;
    else if (!strcmp(a, "--until-finished")) until_finished = 1;
    else if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); return 0; }
    else if (v && !strcmp(a, "--count")) count = strtol(v, NULL, 10), ++i;
    else if (v && !strcmp(a, "--timeout")) timeout_s = strtod(v, NULL), ++i;
    else if (v && !strcmp(a, "--run")) run_filter = strtoll(v, NULL, 10), ++i;
    else if (v && !strcmp(a, "--topic")) {
      want_prob = !strcmp(v, "probabilities") || !strcmp(v, "both");
      want_status = !strcmp(v, "status") || !strcmp(v, "both");
      if (!want_prob && !want_status) { usage(stderr); return 2; }
      ++i;
    } else { usage(stderr); return 2; }
  }
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  setvbuf(stdout, NULL, _IOLBF, 0);  /* a line per sample, also into a pipe */

  participant = dds_create_participant(DDS_DOMAIN_DEFAULT, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "dds_create_participant: %s\n", dds_strretcode(participant));
    return 1;
  }
  /* The bridge's QoS; a volatile reader would also match but would miss the history. */
  qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
  topics[0] = dds_create_topic(participant, &dicesim_dds_probabilities_v3_desc, "dicesim_probabilities", qos, NULL);
  topics[1] = dds_create_topic(participant, &dicesim_dds_run_status_desc, "dicesim_run_status", qos, NULL);
  waitset = dds_create_waitset(participant);
  for (i = 0; i < 2; ++i) {
    readers[i] = 0;
    if ((i == 0 && !want_prob) || (i == 1 && !want_status)) continue;
    readers[i] = dds_create_reader(participant, topics[i], qos, NULL);
    if (topics[i] < 0 || readers[i] < 0) {
      fprintf(stderr, "cannot create reader: %s\n", dds_strretcode(topics[i] < 0 ? topics[i] : readers[i]));
      dds_delete(participant);
      return 1;
    }
    dds_set_status_mask(readers[i], DDS_DATA_AVAILABLE_STATUS);
    dds_waitset_attach(waitset, readers[i], readers[i]);
  }
  dds_delete_qos(qos);

  deadline = timeout_s >= 0 ? started + (dds_duration_t)(timeout_s * 1e9) : DDS_NEVER;
  while (!done && !stop_requested) {
    dds_time_t wake = dds_time() + DDS_MSECS(200); /* to notice Ctrl-C */
    if (deadline != DDS_NEVER && dds_time() >= deadline) {
      exit_code = 3;
      break;
    }
    dds_waitset_wait_until(waitset, NULL, 0, wake < deadline ? wake : deadline);
    for (i = 0; i < 2 && !done; ++i) {
      void* samples[MAX_SAMPLES] = {NULL};
      dds_sample_info_t infos[MAX_SAMPLES];
      int32_t n, k;
      if (readers[i] == 0) continue;
      n = dds_take(readers[i], samples, infos, MAX_SAMPLES, MAX_SAMPLES);
      for (k = 0; k < n && !done; ++k) {
        const int64_t rx = now_utime();
        if (!infos[k].valid_data) continue; /* a disposed or unregistered run */
        if (i == 0) {
          const dicesim_dds_probabilities_v3* m = samples[k];
          if (run_filter && m->run_id != run_filter) continue;
          print_probabilities(m, json, rx);
          if (until_finished && m->finished) done = 1;
        } else {
          const dicesim_dds_run_status* s = samples[k];
          if (run_filter && s->run_id != run_filter) continue;
          print_status(s, json);
        }
        if (count > 0 && ++seen >= count) done = 1;
      }
      if (n > 0) dds_return_loan(readers[i], samples, n);
    }
  }
  dds_delete(participant); /* deletes its topics, readers and waitset too */
  return exit_code;
}
