/* A minimal RAC responder in C: the floor a client is measured against.
 *
 * Answers every CR-terminated line on every connection at once, so a benchmark
 * measures the client, not a Python server: a GET with a reply of its type (I:
 * "0,3,123\r", IO: "0,11,-1\r", P: seven numbers, ...), a PUT with "0\r".  Listens on 127.0.0.1;
 * prints the port it got (argument 0 or none: any free port) and serves until killed.
 * With a second argument "changing", a GET of I answers a counter that grows at every
 * request ("0,3,1\r", "0,3,2\r", ...): every poll of a watched I reads a new value.
 *
 *     cc -O2 -o rac_responder rac_responder.c && ./rac_responder 0 [changing]
 */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#define MAX_CONN 256

static int changing;            /* argument "changing": I answers a growing counter */
static unsigned long counter;   /* the last counter answered */
static char counted[32];        /* "0,3,N\r" */

/* What is known of the line being read on one connection. */
struct line_state {
    int colons;   /* ':' seen so far */
    char first;   /* its first byte: 'G' or 'P' */
    char type[2]; /* the first two bytes of the type field (after the third ':') */
    int typed;    /* bytes of the type field seen */
};

static const char *reply_for(const struct line_state *line, size_t *size) {
    static const char put[] = "0\r", i4[] = "0,3,123\r", io[] = "0,11,-1\r",
                      r4[] = "0,4,1.5\r", r8[] = "0,5,2.25\r", bstr[] = "0,8,abc\r",
                      v[] = "0,8196,1,2,3\r", p[] = "0,8196,350,0,450,180,0,180,5\r",
                      j[] = "0,8196,0,30,90,0,60,0,0,0\r",
                      t[] = "0,8196,350,0,450,1,0,0,0,0,-1,5\r";
    const char *out = i4;
    size_t n = sizeof i4 - 1;
#define PICK(x) (out = (x), n = sizeof(x) - 1)
    if (line->first == 'P') PICK(put);
    else if (line->type[0] == 'I' && line->typed > 1 && line->type[1] == 'O') PICK(io);
    else if (line->type[0] == 'F') PICK(r4);
    else if (line->type[0] == 'D') PICK(r8);
    else if (line->type[0] == 'S') PICK(bstr);
    else if (line->type[0] == 'V') PICK(v);
    else if (line->type[0] == 'P') PICK(p);
    else if (line->type[0] == 'J') PICK(j);
    else if (line->type[0] == 'T') PICK(t);
#undef PICK
    if (changing && out == i4) {
        n = (size_t)snprintf(counted, sizeof counted, "0,3,%lu\r", ++counter % 2000000000UL);
        out = counted;
    }
    *size = n;
    return out;
}

int main(int argc, char **argv) {
    int port = argc > 1 ? atoi(argv[1]) : 0;
    changing = argc > 2 && strcmp(argv[2], "changing") == 0;
    int listener = socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    struct sockaddr_in addr = {0};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons((unsigned short)port);
    if (bind(listener, (struct sockaddr *)&addr, sizeof addr) || listen(listener, 1024)) {
        perror("rac_responder");
        return 1;
    }
    socklen_t len = sizeof addr;
    getsockname(listener, (struct sockaddr *)&addr, &len);
    printf("%d\n", ntohs(addr.sin_port));
    fflush(stdout);

    struct pollfd fds[MAX_CONN + 1];
    struct line_state lines[MAX_CONN + 1];
    int count = 1;
    fds[0].fd = listener;
    fds[0].events = POLLIN;
    char buffer[65536];
    for (;;) {
        if (poll(fds, count, -1) < 0) continue;
        if (fds[0].revents & POLLIN) {
            int conn = accept(listener, NULL, NULL);
            if (conn >= 0 && count <= MAX_CONN) {
                setsockopt(conn, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                fds[count].fd = conn;
                fds[count].events = POLLIN;
                memset(&lines[count], 0, sizeof lines[count]);
                count++;
            } else if (conn >= 0) {
                close(conn);
            }
        }
        for (int i = 1; i < count; i++) {
            if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            ssize_t got = recv(fds[i].fd, buffer, sizeof buffer, 0);
            if (got <= 0) {
                close(fds[i].fd);
                lines[i] = lines[count - 1];
                fds[i] = fds[--count];
                i--;
                continue;
            }
            struct line_state *line = &lines[i];
            for (ssize_t k = 0; k < got; k++) {
                char c = buffer[k];
                if (c == '\r') {
                    size_t size;
                    const char *reply = reply_for(line, &size);
                    send(fds[i].fd, reply, size, MSG_NOSIGNAL);  /* a client may reset */
                    memset(line, 0, sizeof *line);
                } else if (c == ':') {
                    line->colons++;
                } else {
                    if (!line->first) line->first = c;
                    if (line->colons == 3 && line->typed < 2) line->type[line->typed++] = c;
                }
            }
        }
    }
}
