/*
 * The pod sandbox ("pause") process of simtest's real nodes: holds the pod's namespaces, does
 * nothing else. It sleeps until SIGTERM or SIGINT (then exits 0) and reaps every child that is
 * re-parented to it (it is PID 1 of the pod when the pod shares its PID namespace).
 *
 * Built by deploy/docker/build.sh: `gcc -static -Os`, in an image FROM scratch
 * (localhost/simtest/pause:<PAUSE_VERSION>). Our own, so no registry is needed for the sandbox.
 *
 *   pause            sleep until SIGTERM/SIGINT
 *   pause -v         print the version and exit
 */
#define _GNU_SOURCE
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#define PAUSE_VERSION "1.0"

static void on_stop(int signo) {
    (void)signo;
    _exit(0);
}

static void on_child(int signo) {
    (void)signo;
    int saved = errno;
    while (waitpid(-1, NULL, WNOHANG) > 0) {
    }
    errno = saved;
}

static int handle(int signo, void (*handler)(int), int flags) {
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_handler = handler;
    action.sa_flags = flags;
    sigemptyset(&action.sa_mask);
    return sigaction(signo, &action, NULL);
}

int main(int argc, char **argv) {
    if (argc > 1 && strcmp(argv[1], "-v") == 0) {
        printf("pause %s (simtest)\n", PAUSE_VERSION);
        return 0;
    }
    if (argc > 1) {
        fprintf(stderr, "usage: pause [-v]\n");
        return 2;
    }
    if (handle(SIGTERM, on_stop, 0) < 0 || handle(SIGINT, on_stop, 0) < 0
        || handle(SIGCHLD, on_child, SA_NOCLDSTOP | SA_RESTART) < 0) {
        perror("pause: sigaction");
        return 1;
    }
    if (getpid() != 1) {
        fprintf(stderr, "pause: not PID 1; children that are not ours will not be reaped\n");
    }
    for (;;) {
        pause();
    }
}
