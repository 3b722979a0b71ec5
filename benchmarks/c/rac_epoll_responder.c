/* A minimal RAC responder on Linux epoll: the ceiling a server is measured against.
 *
 * Like rac_responder.c (poll), it answers every CR-terminated line on every connection
 * with "0,3,123\r", but the way a fast C server would: epoll (level triggered), and all
 * the replies to one read in one send().  Listens on 127.0.0.1; prints the port it got
 * (argument 0 or none: any free port) and serves until killed.
 *
 *     cc -O2 -o rac_epoll_responder rac_epoll_responder.c && ./rac_epoll_responder 0
 */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#define MAX_EVENTS 256
#define READ_SIZE 4096
#define REPLY "0,3,123\r"
#define REPLY_LEN (sizeof REPLY - 1)

int main(int argc, char **argv) {
    int port = argc > 1 ? atoi(argv[1]) : 0;
    int listener = socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    struct sockaddr_in addr = {0};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons((unsigned short)port);
    if (bind(listener, (struct sockaddr *)&addr, sizeof addr) || listen(listener, 1024)) {
        perror("rac_epoll_responder");
        return 1;
    }
    socklen_t len = sizeof addr;
    getsockname(listener, (struct sockaddr *)&addr, &len);
    printf("%d\n", ntohs(addr.sin_port));
    fflush(stdout);

    int ep = epoll_create1(0);
    struct epoll_event ev = {.events = EPOLLIN, .data.fd = listener};
    epoll_ctl(ep, EPOLL_CTL_ADD, listener, &ev);
    struct epoll_event events[MAX_EVENTS];
    char in[READ_SIZE];
    static char out[READ_SIZE * REPLY_LEN];  /* worst case: a read of nothing but CRs */
    for (;;) {
        int n = epoll_wait(ep, events, MAX_EVENTS, -1);
        for (int i = 0; i < n; i++) {
            int fd = events[i].data.fd;
            if (fd == listener) {
                int conn = accept(listener, NULL, NULL);
                if (conn < 0) continue;
                setsockopt(conn, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                struct epoll_event cev = {.events = EPOLLIN, .data.fd = conn};
                epoll_ctl(ep, EPOLL_CTL_ADD, conn, &cev);
                continue;
            }
            ssize_t got = recv(fd, in, sizeof in, 0);
            if (got <= 0) {  /* closed or reset: closing removes it from the epoll set */
                close(fd);
                continue;
            }
            size_t size = 0;  /* a request split across reads is answered by its CR */
            for (ssize_t k = 0; k < got; k++) {
                if (in[k] == '\r') {
                    memcpy(out + size, REPLY, REPLY_LEN);
                    size += REPLY_LEN;
                }
            }
            if (size) send(fd, out, size, MSG_NOSIGNAL);  /* a benchmark: short sends ignored */
        }
    }
}
