/* Audio recorder for tests and bench audio: one JACK input port that every other client's
 * audio output is connected to (JACK sums them), written with each cycle's frame time.
 * Usage: jack_rec OUT.bin.  File: per cycle int64 mono_us (CLOCK_MONOTONIC when the cycle
 * runs), uint32 nframes, nframes float32.  Stdout: "ready JACK_US MONO_US", at exit "stats
 * XRUNS LOAD_MEAN LOAD_MAX" (JACK's xruns and DSP load, %, sampled every 20 ms) and, per source
 * connected, "connected PORT LATENCY_FRAMES" (the port's playback latency, max) and, at exit,
 * "latency LATENCY_FRAMES": the highest of the sources' latencies read every 20 ms while they
 * were connected, since right after a connection JACK may not have computed it yet (a port
 * not yet connected to the playback ports reads 0). */
#include <jack/jack.h>
#include <jack/ringbuffer.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static jack_client_t *client;
static jack_port_t *port;
static jack_ringbuffer_t *rb;
static volatile sig_atomic_t stop;
static volatile uint32_t dropped;
static volatile uint32_t xruns;

static int on_xrun(void *arg) { (void)arg; xruns++; return 0; }

static int process(jack_nframes_t nframes, void *arg) {
    (void)arg;
    float *buf = (float *)jack_port_get_buffer(port, nframes);
    struct timespec ts; /* when the cycle runs: the dummy driver's DLL time drifts at start */
    clock_gettime(CLOCK_MONOTONIC, &ts);
    int64_t us = (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
    uint32_t n = nframes;
    size_t need = sizeof us + sizeof n + n * sizeof(float);
    if (jack_ringbuffer_write_space(rb) < need) { dropped++; return 0; }
    jack_ringbuffer_write(rb, (char *)&us, sizeof us);
    jack_ringbuffer_write(rb, (char *)&n, sizeof n);
    jack_ringbuffer_write(rb, (char *)buf, n * sizeof(float));
    return 0;
}

static void on_signal(int s) { (void)s; stop = 1; }

static void connect_new(void) {
    const char **ports = jack_get_ports(client, NULL, JACK_DEFAULT_AUDIO_TYPE, JackPortIsOutput);
    if (!ports) return;
    const char *self = jack_port_name(port);
    for (int i = 0; ports[i]; i++) {
        if (strncmp(ports[i], "system:", 7) == 0) continue;
        jack_port_t *src = jack_port_by_name(client, ports[i]);
        if (!src || jack_port_connected_to(src, self)) continue;
        if (jack_connect(client, ports[i], self) == 0) {
            jack_latency_range_t range;
            jack_port_get_latency_range(src, JackPlaybackLatency, &range);
            printf("connected %s %u\n", ports[i], range.max);
            fflush(stdout);
        }
    }
    jack_free(ports);
}

static jack_nframes_t latency_max;

static void read_latency(void) {
    const char **ports = jack_port_get_all_connections(client, port);
    for (int i = 0; ports && ports[i]; i++) {
        jack_port_t *src = jack_port_by_name(client, ports[i]);
        if (!src) continue;
        jack_latency_range_t range;
        jack_port_get_latency_range(src, JackPlaybackLatency, &range);
        if (range.max > latency_max) latency_max = range.max;
    }
    if (ports) jack_free(ports);
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: jack_rec OUT.bin\n"); return 1; }
    FILE *out = fopen(argv[1], "wb");
    if (!out) { perror(argv[1]); return 1; }
    client = jack_client_open("ldrec", JackNoStartServer, NULL);
    if (!client) { fprintf(stderr, "jack_rec: no JACK server\n"); return 1; }
    port = jack_port_register(client, "in", JACK_DEFAULT_AUDIO_TYPE, JackPortIsInput, 0);
    rb = jack_ringbuffer_create(1 << 24);
    jack_set_process_callback(client, process, NULL);
    jack_set_xrun_callback(client, on_xrun, NULL);
    signal(SIGTERM, on_signal);
    signal(SIGINT, on_signal);
    if (jack_activate(client)) { fprintf(stderr, "jack_rec: cannot activate\n"); return 1; }
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    jack_time_t jt = jack_get_time();
    printf("ready %lld %lld\n", (long long)jt,
           (long long)((int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000));
    fflush(stdout);
    char chunk[65536];
    double load_sum = 0, load_max = 0;
    long loads = 0;
    while (!stop) {
        float load = jack_cpu_load(client);
        load_sum += load;
        loads++;
        if (load > load_max) load_max = load;
        connect_new();
        read_latency();
        size_t got;
        while ((got = jack_ringbuffer_read(rb, chunk, sizeof chunk)) > 0) fwrite(chunk, 1, got, out);
        usleep(20000);
    }
    printf("latency %u\n", (unsigned)latency_max);
    jack_deactivate(client);
    size_t got;
    while ((got = jack_ringbuffer_read(rb, chunk, sizeof chunk)) > 0) fwrite(chunk, 1, got, out);
    fclose(out);
    if (dropped) fprintf(stderr, "jack_rec: %u cycles dropped\n", (unsigned)dropped);
    printf("stats %u %.2f %.2f\n", (unsigned)xruns, loads ? load_sum / loads : 0.0, load_max);
    fflush(stdout);
    jack_client_close(client);
    return 0;
}
