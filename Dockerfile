# Tessera farm image: the farm's programs, tessera-render, tessera-info and tessera-keys in
# /usr/local/bin, for compose.yaml under `docker compose` / Docker Swarm. Locally, tessera-up
# runs the same compose.yaml without it.
FROM debian:12
ENV DEBIAN_FRONTEND=noninteractive
WORKDIR /opt/tessera/src
# Packages first, in their own layer, so a source edit does not reinstall them.
COPY setup.sh ./
RUN ./setup.sh deps && rm -rf /var/lib/apt/lists/*
COPY . .
# One image for every x86-64 host: the hot loops pick their instruction set at run time.
RUN cmake -S . -B /opt/tessera/build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON \
 && cmake --build /opt/tessera/build -j"$(nproc)" --target \
      tessera-master tessera-renderer tessera-compositor tessera-display tessera-render tessera-up \
      tessera-info tessera-keys \
 && cd /opt/tessera/build/bin \
 && install -m 0755 tessera-master tessera-renderer tessera-compositor tessera-display \
      tessera-render tessera-up tessera-info tessera-keys /usr/local/bin/
# Scene paths in compose.yaml (scenes/...) are relative to the source tree.
WORKDIR /opt/tessera/src
CMD ["tessera-up", "--help"]
