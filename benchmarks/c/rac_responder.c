/* A minimal RAC responder in C: the floor a client is measured against.
 *
 * Answers every CR-terminated line on every connection with "0,3,123\r" at once,
 * so a benchmark measures the client, not a Python server.  Listens on 127.0.0.1;
 * prints the port it got (argument 0 or none: any free port) and serves until killed.
 *
 *     cc -O2 -o rac_responder rac_responder.c && ./rac_responder 0
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
        perror("rac_responder");
        return 1;
    }
    socklen_t len = sizeof addr;
    getsockname(listener, (struct sockaddr *)&addr, &len);
    printf("%d\n", ntohs(addr.sin_port));
    fflush(stdout);

    struct pollfd fds[MAX_CONN + 1];
    int count = 1;
    fds[0].fd = listener;
    fds[0].events = POLLIN;
    static const char reply[] = "0,3,123\r";
    char buffer[65536];
    for (;;) {
        if (poll(fds, count, -1) < 0) continue;
        if (fds[0].revents & POLLIN) {
            int conn = accept(listener, NULL, NULL);
            if (conn >= 0 && count <= MAX_CONN) {
                setsockopt(conn, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                fds[count].fd = conn;
                fds[count].events = POLLIN;
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
                fds[i] = fds[--count];
                i--;
                continue;
            }
            for (ssize_t k = 0; k < got; k++) {
                if (buffer[k] == '\r') send(fds[i].fd, reply, sizeof reply - 1, 0);
            }
        }
    }
}
