/* Minimal RAC load client, the floor the Python client is compared with.
 *
 *   rac_client PORT SESSIONS SECONDS
 *
 * Opens SESSIONS connections to 127.0.0.1:PORT, keeps exactly one request in flight on
 * each (the protocol's rule) and prints the completed requests per second. */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec / 1e9;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: rac_client PORT SESSIONS SECONDS\n");
        return 2;
    }
    int port = atoi(argv[1]), sessions = atoi(argv[2]);
    double seconds = atof(argv[3]);
    static const char request[] = "GET:RC8:10:I:\r";
    struct pollfd *fds = calloc(sessions, sizeof *fds);
    struct sockaddr_in address = {.sin_family = AF_INET, .sin_port = htons(port)};
    inet_pton(AF_INET, "127.0.0.1", &address.sin_addr);
    for (int i = 0; i < sessions; i++) {
        int fd = socket(AF_INET, SOCK_STREAM, 0), one = 1;
        setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        if (connect(fd, (struct sockaddr *)&address, sizeof address) != 0) {
            perror("connect");
            return 1;
        }
        fds[i].fd = fd;
        fds[i].events = POLLIN;
        if (write(fd, request, sizeof request - 1) < 0) return 1;
    }
    long done = 0;
    char buffer[4096];
    double start = now(), end = start + seconds;
    while (now() < end) {
        if (poll(fds, sessions, 100) <= 0) continue;
        for (int i = 0; i < sessions; i++) {
            if (!(fds[i].revents & POLLIN)) continue;
            ssize_t n = read(fds[i].fd, buffer, sizeof buffer);
            if (n <= 0) return 1;
            for (ssize_t k = 0; k < n; k++) {
                if (buffer[k] == '\r') {
                    done++;
                    if (write(fds[i].fd, request, sizeof request - 1) < 0) return 1;
                }
            }
        }
    }
    printf("%.1f\n", done / (now() - start));
    return 0;
}
