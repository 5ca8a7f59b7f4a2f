# A swarm node for scripts/test-swarm.sh: Debian 12 with its own Docker Engine (Debian's
# docker.io: dockerd 20.10 with containerd, runc and iptables), run as a container of the host
# Engine, one per node. It needs no build context:
#   docker build --build-arg BASE_IMAGE=debian:12 -t sensornet-node - <docker/node.Dockerfile
#   docker run -d --init --privileged --cgroupns private -v VOLUME:/var/lib/docker sensornet-node
#
# - dockerd is the command, under the host's docker-init (`docker run --init`), which forwards
#   the stop signal and reaps;
# - /var/lib/docker must be a volume (a directory of the host's file system): the nested
#   Engine's overlay2 cannot stack on the node container's own overlay root;
# - on a cgroup v1 host, where `--privileged` cannot be used (scripts/test-swarm.sh: a machine
#   whose capability bounding set lacks one that runc would grant), the container gets every
#   capability there is with seccomp and the /proc masks off instead, and its /sys and cgroup
#   hierarchies come mounted read-only: the command makes them writable first (the nested
#   runc creates its containers' cgroups there). Under --privileged that is a no-op. A cgroup v2
#   host would need the nesting set-up of the docker:dind image instead; not handled here.
ARG BASE_IMAGE=debian:12
FROM ${BASE_IMAGE}
ENV DEBIAN_FRONTEND=noninteractive
RUN apt-get update -qq \
    && apt-get install -y -qq --no-install-recommends docker.io iptables iproute2 procps \
    && rm -rf /var/lib/apt/lists/*
VOLUME /var/lib/docker
CMD ["sh", "-c", "mount -o remount,rw /sys && for m in /sys/fs/cgroup/*; do mount -o remount,bind,rw \"$m\"; done && exec dockerd --storage-driver=overlay2"]
