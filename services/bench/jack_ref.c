/* Reference JACK MIDI client for bench input_load: stamps every event in the process thread. */
#include <jack/jack.h>
#include <jack/midiport.h>
#include <jack/ringbuffer.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <signal.h>

typedef struct { int64_t frame_us; int64_t mono_ns; uint8_t b[3]; uint8_t n; } rec_t;
static jack_client_t *client;
static jack_port_t *port;
static jack_ringbuffer_t *rb;
static volatile sig_atomic_t stop;

static int process(jack_nframes_t nframes, void *arg) {
    (void)arg;
    void *buf = jack_port_get_buffer(port, nframes);
    uint32_t n = jack_midi_get_event_count(buf);
    jack_nframes_t base = jack_last_frame_time(client);
    for (uint32_t i = 0; i < n; i++) {
        jack_midi_event_t ev;
        if (jack_midi_event_get(&ev, buf, i) != 0) continue;
        rec_t r;
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        r.mono_ns = (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
        r.frame_us = (int64_t)jack_frames_to_time(client, base + ev.time);
        r.n = ev.size < 3 ? (uint8_t)ev.size : 3;
        memset(r.b, 0, 3);
        memcpy(r.b, ev.buffer, r.n);
        if (jack_ringbuffer_write_space(rb) >= sizeof r) jack_ringbuffer_write(rb, (char *)&r, sizeof r);
    }
    return 0;
}

static void on_signal(int s) { (void)s; stop = 1; }

int main(int argc, char **argv) {
    const char *src = argc > 1 ? argv[1] : NULL;
    client = jack_client_open("ldref", JackNoStartServer, NULL);
    if (!client) { fprintf(stderr, "ldref: no JACK server\n"); return 1; }
    port = jack_port_register(client, "in", JACK_DEFAULT_MIDI_TYPE, JackPortIsInput, 0);
    rb = jack_ringbuffer_create(1 << 22);
    jack_ringbuffer_mlock(rb);
    jack_set_process_callback(client, process, NULL);
    signal(SIGTERM, on_signal);
    signal(SIGINT, on_signal);
    if (jack_activate(client)) { fprintf(stderr, "ldref: cannot activate\n"); return 1; }
    if (src && jack_connect(client, src, jack_port_name(port))) {
        fprintf(stderr, "ldref: cannot connect %s\n", src); return 1;
    }
    /* The JACK clock against CLOCK_MONOTONIC, so frame times can be put on the shared clock. */
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    jack_time_t jt = jack_get_time();
    printf("ready %lld %lld\n", (long long)jt, (long long)((int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000));
    fflush(stdout);
    while (!stop) {
        rec_t r;
        while (jack_ringbuffer_read_space(rb) >= sizeof r) {
            jack_ringbuffer_read(rb, (char *)&r, sizeof r);
            printf("%lld %lld %u %u %u\n", (long long)r.frame_us, (long long)r.mono_ns, r.b[0], r.b[1], r.b[2]);
        }
        fflush(stdout);
        usleep(2000);
    }
    jack_client_close(client);
    return 0;
}
